# Provenance: the git hash is regenerated on every build (not just at configure time), and the
# generated file is only rewritten when it changes, so it does not force a relink of everything.
set(PRTLAB_VERSION_CPP ${CMAKE_BINARY_DIR}/generated/prtlab_build_info.cpp)
add_custom_target(prtlab_build_info_gen
  COMMAND ${CMAKE_COMMAND}
    -DSOURCE_DIR=${CMAKE_SOURCE_DIR}
    -DOUTPUT=${PRTLAB_VERSION_CPP}
    -DVERSION=${PROJECT_VERSION}
    -DBUILD_TYPE=${CMAKE_BUILD_TYPE}
    -DCOMPILER_ID=${CMAKE_CXX_COMPILER_ID}
    -DCOMPILER_VERSION=${CMAKE_CXX_COMPILER_VERSION}
    -P ${CMAKE_CURRENT_LIST_DIR}/write_build_info.cmake
  BYPRODUCTS ${PRTLAB_VERSION_CPP}
  COMMENT "prtlab: build info (git hash)")
