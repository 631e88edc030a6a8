# PRTLAB_ARCH: the instruction set prtlab's own code (and the Eigen kernels inlined into it) is
# compiled for (docs/build-options.md).
#   portable    the x86-64 baseline (SSE2): a binary that runs on any x86-64 machine, the one to
#               carry to another machine (scripts/gpu-bundle.sh, clusters of mixed nodes)
#   x86-64-v3   AVX2, FMA, BMI2 (Intel Haswell, AMD Zen and later)
#   native      every extension of the machine that builds (-march=native)
# Debian's libraries (Embree, TBB, OpenBLAS) pick their kernels at run time whatever this says.
set(PRTLAB_ARCH portable CACHE STRING "Target instruction set: portable, x86-64-v3 or native")
set_property(CACHE PRTLAB_ARCH PROPERTY STRINGS portable x86-64-v3 native)
if(PRTLAB_ARCH STREQUAL "portable")
  set(PRTLAB_ARCH_FLAGS "")
elseif(PRTLAB_ARCH STREQUAL "x86-64-v3")
  set(PRTLAB_ARCH_FLAGS -march=x86-64-v3)
elseif(PRTLAB_ARCH STREQUAL "native")
  set(PRTLAB_ARCH_FLAGS -march=native)
else()
  message(FATAL_ERROR "PRTLAB_ARCH='${PRTLAB_ARCH}': use portable, x86-64-v3 or native")
endif()
if(PRTLAB_ARCH_FLAGS)
  include(CheckCXXCompilerFlag)
  check_cxx_compiler_flag("${PRTLAB_ARCH_FLAGS}" PRTLAB_ARCH_FLAGS_WORK)
  if(NOT PRTLAB_ARCH_FLAGS_WORK)
    message(FATAL_ERROR "PRTLAB_ARCH=${PRTLAB_ARCH}: the compiler refuses ${PRTLAB_ARCH_FLAGS}")
  endif()
  add_compile_options(${PRTLAB_ARCH_FLAGS})
  # GCC 12 reports Eigen's own AVX / AVX-512 reductions (predux, the blocked bidiagonalisation)
  # as maybe-uninitialized once they are inlined into our code: false positives inside Eigen,
  # which would otherwise be the only warnings of these builds.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    add_compile_options(-Wno-maybe-uninitialized)
  endif()
endif()
message(STATUS "prtlab: PRTLAB_ARCH=${PRTLAB_ARCH} ${PRTLAB_ARCH_FLAGS}")
