# SPDX-License-Identifier: MIT
# ctest conformance_spec_decoder_nodes: spec_decoder.py against the reference decoder on streams
# of the draft format 13 (spec/format.md sections 8 and 15): groups continued across chunks,
# streams in nodes with and without attributes, and streams derived from one by editing its
# NODE chunk (derive_node_streams.py). The reference writes each .expected.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
# name, source mesh, pmz-encode options (separated by ",")
set(streams
  "terrain-nodes terrain.obj --position-bits,12,--cluster-vertices,100"
  "seamed-nodes seamed.obj --cluster-vertices,60"
  "seamed-carry seamed.obj -q")
foreach(s IN LISTS streams)
  string(REPLACE " " ";" parts "${s}")
  list(GET parts 0 name)
  list(GET parts 1 mesh)
  list(GET parts 2 opts)
  string(REPLACE "," ";" opts "${opts}")
  execute_process(COMMAND ${ENCODE} ${DIR}/meshes/${mesh} -o ${WORK}/${name}.pmz ${opts} -q
    RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pmz-encode ${mesh} failed: ${err}")
  endif()
endforeach()
execute_process(COMMAND ${PYTHON} ${DIR}/derive_node_streams.py ${WORK}/seamed-nodes.pmz ${WORK}
  RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "derive_node_streams.py failed: ${err}")
endif()
file(GLOB made ${WORK}/*.pmz)
foreach(f IN LISTS made)
  execute_process(COMMAND ${CONFORMANCE} expect ${f} "made by spec_decoder_nodes.cmake"
    RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pmz-conformance expect ${f} failed: ${err}")
  endif()
endforeach()
execute_process(COMMAND ${PYTHON} ${DIR}/spec_decoder.py ${WORK}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "spec_decoder.py disagrees with the reference decoder:\n${out}${err}")
endif()
