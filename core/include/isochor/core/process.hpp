// Another program run as a child process: its arguments, its environment and its log.
#pragma once
#include <sys/types.h>

#include <functional>
#include <string>
#include <vector>

namespace isochor {

// Starts args[0] (looked up on PATH unless it holds a '/') with stdin from /dev/null and stdout
// and stderr into `log`; its environment is this process's without the variables `drop` names
// ("NAME=value" strings), plus `extra`. Returns 0 and the child's pid, or the error number of a
// start that failed.
int spawn_logged(std::vector<std::string> args, const std::string& log,
                 const std::function<bool(const std::string&)>& drop, const std::vector<std::string>& extra,
                 pid_t& pid);

}  // namespace isochor
