# vmmlib (Debian libvmmlib-dev, header-only) for srbf_cta's tests only: its Tucker3 HOSVD and HOOI
# (vmmlib_tucker.h) are the independent implementation the N-mode SVD is checked against. Its
# headers call LAPACK's Fortran routines (dgesvd_, dsyevx_; liblapack-dev) and CBLAS (cblas_dgemm,
# cblas_sgemm and cblas_*dot from <cblas.h>; Debian's libblas-dev ships that header and has the
# symbols in libblas). Without all three the test builds and skips that comparison, saying why.
find_path(PRTLAB_VMMLIB_INCLUDE_DIR vmmlib/t3_hooi.hpp)
find_path(PRTLAB_CBLAS_INCLUDE_DIR cblas.h)
find_package(LAPACK QUIET)  # finds BLAS too
if(PRTLAB_VMMLIB_INCLUDE_DIR AND PRTLAB_CBLAS_INCLUDE_DIR AND LAPACK_FOUND AND BLAS_FOUND)
  # FindBLAS may settle on a BLAS without the C interface; vmmlib needs both in one link.
  include(CheckSymbolExists)
  include(CMakePushCheckState)
  cmake_push_check_state(RESET)
  set(CMAKE_REQUIRED_INCLUDES ${PRTLAB_CBLAS_INCLUDE_DIR})
  set(CMAKE_REQUIRED_LIBRARIES LAPACK::LAPACK BLAS::BLAS)
  set(CMAKE_REQUIRED_QUIET ON)
  check_symbol_exists(cblas_dgemm cblas.h PRTLAB_BLAS_HAS_CBLAS)
  cmake_pop_check_state()
endif()
if(PRTLAB_VMMLIB_INCLUDE_DIR AND PRTLAB_CBLAS_INCLUDE_DIR AND PRTLAB_BLAS_HAS_CBLAS)
  target_include_directories(${PRTLAB_TEST_TARGET} SYSTEM PRIVATE
    ${PRTLAB_VMMLIB_INCLUDE_DIR} ${PRTLAB_CBLAS_INCLUDE_DIR})
  target_link_libraries(${PRTLAB_TEST_TARGET} PRIVATE LAPACK::LAPACK BLAS::BLAS)
  target_compile_definitions(${PRTLAB_TEST_TARGET} PRIVATE PRTLAB_HAVE_VMMLIB=1)
else()
  message(WARNING "vmmlib, LAPACK or CBLAS not found (install libvmmlib-dev liblapack-dev libblas-dev): ${PRTLAB_TEST_TARGET} skips the comparison with vmmlib's Tucker3 HOSVD/HOOI")
endif()
