# GSL (Debian libgsl-dev, listed in ../packages.txt) for haar_test only: its non-standard 2D Haar
# transform (gsl_wavelet2d_nstransform) is the independent implementation the face transform is
# checked against. Without it the test builds and skips that comparison, saying why.
find_package(GSL QUIET)
if(GSL_FOUND)
  target_link_libraries(${PRTLAB_TEST_TARGET} PRIVATE GSL::gsl)
  target_compile_definitions(${PRTLAB_TEST_TARGET} PRIVATE PRTLAB_HAVE_GSL=1)
else()
  message(WARNING "GSL not found (install libgsl-dev; scripts/setup.sh does): haar_test skips the comparison with gsl_wavelet2d_nstransform")
endif()
