# SPDX-License-Identifier: MIT
# ctest gltf_example: scripts/pmz_to_glb.py reproduces docs/gltf/torus.glb, and the GLB carries
# the whole stream: decoded from the GLB's bytes, every level of the vector's .expected file and
# the full mesh the extension announces (check_glb_stream.py).
execute_process(COMMAND ${PYTHON} ${SCRIPT} --decoder ${DECODE} ${INPUT} -o ${OUT}
  RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "pmz_to_glb.py failed: ${err}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUT} ${EXPECTED} RESULT_VARIABLE same)
if(NOT same EQUAL 0)
  message(FATAL_ERROR "${OUT} differs from ${EXPECTED} (regenerate: see docs/gltf-binding.md)")
endif()
# The GLB header: magic "glTF", version 2, total length = the file's size.
file(READ ${OUT} hex HEX)
file(SIZE ${OUT} size)
string(SUBSTRING "${hex}" 0 16 head)
string(SUBSTRING "${hex}" 16 8 len)
string(REGEX REPLACE "(..)(..)(..)(..)" "\\4\\3\\2\\1" len "${len}")
math(EXPR len "0x${len}")
if(NOT head STREQUAL "676c544602000000" OR NOT len EQUAL size)
  message(FATAL_ERROR "${OUT}: not a GLB 2.0 header of its size (${head}, ${len} vs ${size})")
endif()
# The stream inside the GLB, decoded to the full mesh and the levels between.
execute_process(COMMAND ${PYTHON} ${CHECK} --decoder ${DECODE} --stream ${INPUT}
  --expected ${LEVELS} ${OUT} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${OUT}: the stream it carries does not decode as its vector:\n${err}")
endif()
