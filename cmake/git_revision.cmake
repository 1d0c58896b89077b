# Run at build time (not configure time): writes OUT with the source tree's git revision, and only
# when it changed, so that every output file names the revision that was built, not the one that
# was configured. Inputs: SRC (the source tree), OUT (the header), GIT (the git executable).
set(rev "unknown")
if(GIT AND EXISTS "${SRC}/.git")
  execute_process(COMMAND "${GIT}" describe --always --dirty --abbrev=12 WORKING_DIRECTORY "${SRC}"
                  OUTPUT_VARIABLE rev OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE failed)
  if(failed OR rev STREQUAL "")
    set(rev "unknown")
  endif()
endif()
set(text "// Generated at build time by cmake/git_revision.cmake.\n#pragma once\n#define ISOCHOR_GIT_REVISION \"${rev}\"\n")
set(old "")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old)
endif()
if(NOT old STREQUAL text)
  file(WRITE "${OUT}" "${text}")
endif()
