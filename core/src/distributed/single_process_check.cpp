// The communicator as a build without MPI compiles it (CMake builds this object only when MPI is
// found, so the single-process branch keeps compiling).
#undef PRTLAB_HAVE_MPI
#include "communicator.cpp"
