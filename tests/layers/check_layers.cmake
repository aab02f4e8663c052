# Builds the layer probes (tests/layers/CMakeLists.txt): every control must compile; every probe that
# includes a header of a layer above must fail, with the compiler saying that header is not found.
# cmake -DBUILD_DIR=... -DCONTROLS=a;b -DFORBIDDEN=c;d -DEXPECT=c=header;d=header -DKEEP_GOING=-k -P check_layers.cmake
cmake_minimum_required(VERSION 3.20)
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD_DIR} --target ${CONTROLS}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "a probe that includes only layers it may use does not build:\n${out}")
endif()
list(LENGTH CONTROLS controls)
message(STATUS "${controls} probes that include their own and lower layers build")

execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD_DIR} --target ${FORBIDDEN} -- ${KEEP_GOING}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(rc EQUAL 0)
  message(FATAL_ERROR "the probes that include a layer above built:\n${out}")
endif()
set(missing)
foreach(pair IN LISTS EXPECT)
  string(REPLACE "=" ";" pair "${pair}")
  list(GET pair 0 probe)
  list(GET pair 1 header)
  string(REPLACE "." "\\." header_re "${header}")
  # gcc: "x.cpp:2:10: fatal error: render/camera.h: No such file or directory"; clang: "'render/camera.h' file not found".
  if(NOT out MATCHES "${probe}\\.cpp:[0-9]+:[0-9]+: fatal error: '?${header_re}'?:? (No such file or directory|file not found)")
    list(APPEND missing "${probe} (${header})")
  endif()
endforeach()
if(missing)
  message(FATAL_ERROR "these probes did not fail for want of the header they include: ${missing}\n${out}")
endif()
list(LENGTH EXPECT forbidden)
message(STATUS "${forbidden} probes that include a layer above (or the public API) fail: header not found")
