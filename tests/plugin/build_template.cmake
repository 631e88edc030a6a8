# Configure and build examples/plugin-template against a prtlab build tree (ctest fixture
# plugin.template_build, tests/plugin/CMakeLists.txt). Arguments (-D): SOURCE, BINARY,
# PRTLAB_DIR, GENERATOR, CXX_COMPILER, CXX_COMPILER_LAUNCHER, CXX_FLAGS, MODULE_LINKER_FLAGS,
# EXPECTED (the plugin file the build must produce).
foreach(var SOURCE BINARY PRTLAB_DIR GENERATOR CXX_COMPILER EXPECTED)
  if(NOT ${var})
    message(FATAL_ERROR "build_template.cmake: -D${var}=... is required")
  endif()
endforeach()

function(run what)
  string(TIMESTAMP start "%s")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  string(TIMESTAMP end "%s")
  math(EXPR seconds "${end} - ${start}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "plugin template: ${what} failed (${rc}): ${ARGN}")
  endif()
  message(STATUS "plugin template: ${what} took ${seconds} s")
endfunction()

# A stale plugin must not pass for a fresh one.
file(REMOVE ${EXPECTED})
run(configure ${CMAKE_COMMAND} -S ${SOURCE} -B ${BINARY} -G ${GENERATOR}
  -DCMAKE_BUILD_TYPE=Release
  -DCMAKE_CXX_FLAGS_RELEASE=-O1
  -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
  -DCMAKE_CXX_COMPILER_LAUNCHER=${CXX_COMPILER_LAUNCHER}
  -DCMAKE_CXX_FLAGS=${CXX_FLAGS}
  -DCMAKE_MODULE_LINKER_FLAGS=${MODULE_LINKER_FLAGS}
  -Dprtlab_DIR=${PRTLAB_DIR})
run(build ${CMAKE_COMMAND} --build ${BINARY} -j 2)
if(NOT EXISTS ${EXPECTED})
  message(FATAL_ERROR "plugin template: the build did not produce ${EXPECTED}")
endif()
