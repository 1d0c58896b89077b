// The one way isochor quotes a word for /bin/sh: the resume command it prints, and the commands it
// runs for its Python and Blender tools.
#pragma once
#include <string>

namespace isochor {

// `word` as one shell word: as it is when it holds only characters that the shell takes
// literally (letters, digits and -_./:=+,@%), else in single quotes with each ' written '\''.
std::string shell_quoted(const std::string& word);

}  // namespace isochor
