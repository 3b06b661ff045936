# Writes the source tree's git commit into OUT (a one-function C++ file) when it changed, so a new commit
# rebuilds one small file. Run at every build by the isplat_build_info target; "unknown" without git.
execute_process(COMMAND git -C "${SRC}" rev-parse --short=12 HEAD OUTPUT_VARIABLE commit
                OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc ERROR_QUIET)
if(NOT rc EQUAL 0 OR commit STREQUAL "")
  set(commit "unknown")
else()
  execute_process(COMMAND git -C "${SRC}" status --porcelain --untracked-files=no OUTPUT_VARIABLE changes ERROR_QUIET)
  if(NOT changes STREQUAL "")
    set(commit "${commit}-dirty")  # built with uncommitted changes to tracked files
  endif()
endif()
set(text "// Generated at build time by cmake/build_info.cmake.\n#include \"core/build_info.h\"\n\nconst char* isplat::build_commit() {\n  return \"${commit}\";\n}\n")
set(old "")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old)
endif()
if(NOT old STREQUAL text)
  file(WRITE "${OUT}" "${text}")
endif()
