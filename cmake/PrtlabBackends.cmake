# prtlab_add_backend(<folder> [TEST_ONLY])
#
# One backend = one folder: its *.cpp (one OBJECT library, so every static registrar
# PRT_REGISTER_COMPRESSOR / PRT_REGISTER_MATERIAL is linked into every program: nothing is dropped
# by the linker), its *.cl kernels (embedded into that library and registered under their file
# names, which must start with the folder's name), its tests (<folder>/tests/*_test.cpp, built
# like every test by tests/CMakeLists.txt), its doc page (<folder>/README.md) and, when it needs
# one, <folder>/deps.cmake: included with PRTLAB_BACKEND_TARGET set to the backend's target, it
# finds and links the backend's own third-party libraries, which no other backend then sees.
#
# Built-in backends (compressors/<name>/) go into every program through the INTERFACE library
# prtlab_compressors; TEST_ONLY backends (tests/backends/<name>/) through prtlab_test_backends,
# which only the tests and the test build of the CLI link.
include(EmbedKernels)

function(prtlab_add_backend dir)
  cmake_parse_arguments(ARG "TEST_ONLY" "" "" ${ARGN})
  get_filename_component(name ${dir} NAME)
  if(NOT name MATCHES "^[a-z][a-z0-9_-]*$")
    message(FATAL_ERROR "${dir}: a backend folder is named like its backend: lower case letters, digits, '-' and '_'")
  endif()
  string(MAKE_C_IDENTIFIER ${name} id)
  set(target prtlab_backend_${id})
  file(GLOB sources CONFIGURE_DEPENDS ${dir}/*.cpp)
  if(NOT sources)
    message(FATAL_ERROR "${dir}: a backend folder needs at least one .cpp file")
  endif()
  add_library(${target} OBJECT ${sources})
  target_link_libraries(${target} PUBLIC prtlab_core PRIVATE prtlab_warnings)
  # Tests and benches include a backend's headers as "<name>/<file>.h".
  get_filename_component(parent ${dir} DIRECTORY)
  target_include_directories(${target} PUBLIC ${parent})

  file(GLOB kernels CONFIGURE_DEPENDS ${dir}/*.cl)
  foreach(k IN LISTS kernels)
    get_filename_component(kname ${k} NAME_WLE)
    string(FIND "${kname}" "${id}" at)
    string(FIND "${kname}" "${name}" at_name)
    if(NOT at EQUAL 0 AND NOT at_name EQUAL 0)
      message(FATAL_ERROR "${k}: a backend's kernel files are named after it (${name}*.cl), so that no two backends register the same kernel name")
    endif()
  endforeach()
  if(kernels)
    set(generated ${CMAKE_BINARY_DIR}/generated/kernels_${id}.cpp)
    prtlab_embed_kernels(KERNEL_DIR ${dir} OUTPUT ${generated})
    target_sources(${target} PRIVATE ${generated})
  endif()

  if(EXISTS ${dir}/deps.cmake)
    set(PRTLAB_BACKEND_TARGET ${target})
    set(PRTLAB_BACKEND_DIR ${dir})
    include(${dir}/deps.cmake)
  endif()

  file(GLOB tests CONFIGURE_DEPENDS ${dir}/tests/*_test.cpp)
  if(ARG_TEST_ONLY)
    set_property(GLOBAL APPEND PROPERTY PRTLAB_TEST_BACKEND_TARGETS ${target})
  else()
    set_property(GLOBAL APPEND PROPERTY PRTLAB_BACKEND_TARGETS ${target})
  endif()
  set_property(GLOBAL APPEND PROPERTY PRTLAB_BACKEND_TEST_SOURCES ${tests})
endfunction()

# prtlab_collect_backends(<interface target> <global property>): an INTERFACE library whose
# consumers link the objects of every backend in the property.
function(prtlab_collect_backends target property)
  add_library(${target} INTERFACE)
  get_property(backends GLOBAL PROPERTY ${property})
  foreach(b IN LISTS backends)
    target_sources(${target} INTERFACE $<TARGET_OBJECTS:${b}>)
    target_link_libraries(${target} INTERFACE ${b})
  endforeach()
endfunction()
