# SPDX-License-Identifier: MIT
# Strips a copy of the shared decoder library and fails if it is LIMIT bytes or more.
execute_process(COMMAND ${STRIP} -o ${OUT} ${LIB} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "strip failed on ${LIB}")
endif()
file(SIZE ${OUT} size)
message(STATUS "stripped ${LIB}: ${size} bytes (limit ${LIMIT})")
if(NOT size LESS LIMIT)
  message(FATAL_ERROR "stripped decoder library is ${size} bytes, the budget is under ${LIMIT}")
endif()
