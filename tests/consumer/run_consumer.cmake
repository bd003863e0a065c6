# SPDX-License-Identifier: MIT
# Configures, builds and runs one consumer project (CONSUMER_SOURCE) against the pmz installed
# in PREFIX. CONFIGURE_ARGS: extra -D options; EXPECT_SHARED: the program must load
# libpmz_decoder.so (else it must not).
file(REMOVE_RECURSE ${WORK_DIR})
# A sanitizer build installs instrumented libraries: the consumer links the runtime too.
set(sanitize "")
if(PMZ_SANITIZE)
  set(sanitize "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=${PMZ_SANITIZE}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE} -B ${WORK_DIR}
                -DCMAKE_PREFIX_PATH=${PREFIX} ${sanitize} ${CONFIGURE_ARGS} RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "configuring the consumer failed: ${rc}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR} RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "building the consumer failed: ${rc}")
endif()

execute_process(COMMAND ldd ${WORK_DIR}/decode OUTPUT_VARIABLE libs RESULT_VARIABLE rc)
if(rc EQUAL 0)
  if(EXPECT_SHARED AND NOT libs MATCHES "libpmz_decoder\\.so")
    message(FATAL_ERROR "decode does not load libpmz_decoder.so:\n${libs}")
  elseif(NOT EXPECT_SHARED AND libs MATCHES "libpmz_decoder\\.so")
    message(FATAL_ERROR "decode loads libpmz_decoder.so, expected the static library")
  endif()
endif()

set(input ${SAMPLE})
if(EXISTS ${WORK_DIR}/encode)
  set(input ${WORK_DIR}/grid.pmz)
  execute_process(COMMAND ${WORK_DIR}/encode ${input} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "the encoder consumer failed: ${rc}")
  endif()
endif()
# Tiny slices, then the README's 64 KiB reads.
foreach(slice 7 65536)
  execute_process(COMMAND ${WORK_DIR}/decode ${input} ${slice} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "the consumer failed on ${input} in slices of ${slice}: ${rc}")
  endif()
endforeach()
