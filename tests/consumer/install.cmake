# SPDX-License-Identifier: MIT
# Installs the build tree into PREFIX (fresh).
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${PMZ_BINARY_DIR} --prefix ${PREFIX}
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "cmake --install failed: ${rc}")
endif()
# The codec's internal headers stay out of the installed surface.
file(GLOB_RECURSE headers RELATIVE ${PREFIX}/include ${PREFIX}/include/*)
list(SORT headers)
message(STATUS "installed headers: ${headers}")
foreach(h IN LISTS headers)
  if(NOT h MATCHES "^pmz/(decoder\\.hpp|pmz\\.h|export\\.h|status\\.hpp|mesh\\.hpp|simplify\\.hpp|writer\\.hpp|openmesh\\.hpp)$")
    message(FATAL_ERROR "installed header outside the public API: ${h}")
  endif()
endforeach()
