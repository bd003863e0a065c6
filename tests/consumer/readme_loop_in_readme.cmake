# SPDX-License-Identifier: MIT
# The README's embedding loop is the compiled one: the lines between "// README:begin" and
# "// README:end" in readme_loop.hpp (less their indentation) appear verbatim in README.md.
file(READ ${LOOP} source)
string(REGEX MATCH "// README:begin\n(.*)\n *// README:end" _ "${source}")
set(block "${CMAKE_MATCH_1}")
if(block STREQUAL "")
  message(FATAL_ERROR "${LOOP}: no README:begin / README:end block")
endif()
# (CMake's ^ also matches where a repeated search resumes: strip after newlines only.)
string(REPLACE "\n  " "\n" block "\n${block}")
string(SUBSTRING "${block}" 1 -1 block)
file(READ ${README} readme)
string(FIND "${readme}" "${block}" at)
if(at LESS 0)
  message(FATAL_ERROR "README.md does not contain the loop of ${LOOP} verbatim:\n${block}")
endif()
message(STATUS "README.md has the compiled loop at offset ${at}")
