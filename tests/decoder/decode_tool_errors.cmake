# pmz-decode on bad input: one-line error, non-zero exit, no output file; --salvage writes the
# last good level of a truncated stream and still exits non-zero.
set(out ${WORK}/out.obj)
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
file(READ ${SAMPLE} hex HEX)
string(SUBSTRING "${hex}" 0 600 hex)  # first 300 bytes: base mesh in, splits cut off
execute_process(COMMAND ${PYTHON} -c "import sys; open(sys.argv[1],'wb').write(bytes.fromhex(sys.argv[2]))"
                ${WORK}/trunc.pmz ${hex})

execute_process(COMMAND ${DECODE} ${WORK}/trunc.pmz -o ${out} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR EXISTS ${out})
  message(FATAL_ERROR "truncated stream: expected failure and no output, got rc=${rc}")
endif()
if(NOT err MATCHES "truncated")
  message(FATAL_ERROR "truncated stream: message does not say so: ${err}")
endif()

execute_process(COMMAND ${DECODE} ${WORK}/trunc.pmz -o ${out} --salvage RESULT_VARIABLE rc)
if(rc EQUAL 0 OR NOT EXISTS ${out})
  message(FATAL_ERROR "--salvage: expected non-zero exit and an output file, got rc=${rc}")
endif()
file(STRINGS ${out} faces REGEX "^f ")
list(LENGTH faces nfaces)
if(nfaces LESS 1)
  message(FATAL_ERROR "--salvage wrote no faces")
endif()

file(REMOVE ${out})
execute_process(COMMAND ${DECODE} ${SAMPLE} -o ${out} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR NOT EXISTS ${out})
  message(FATAL_ERROR "whole sample: expected success, got rc=${rc}")
endif()
