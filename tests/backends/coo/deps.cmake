# A backend's own third-party dependencies, applied to its objects only (cmake/PrtlabBackends.cmake
# includes this file with PRTLAB_BACKEND_TARGET set). `coo` needs none; it links the threads
# library and sets a definition so that its test can see that this file took effect.
find_package(Threads REQUIRED)
target_link_libraries(${PRTLAB_BACKEND_TARGET} PRIVATE Threads::Threads)
target_compile_definitions(${PRTLAB_BACKEND_TARGET} PRIVATE PRTLAB_COO_DEPS_APPLIED)
