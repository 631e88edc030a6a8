# hf needs no third-party library. What this adds is the measurement program of
# compressors/hf/tools/ (README.md "Halfway interpolation"): it is not part of the backend's
# object library (a main() there would be linked into every program), so it is built here.
add_executable(hf_interpolation ${PRTLAB_BACKEND_DIR}/tools/hf_interpolation.cpp)
target_link_libraries(hf_interpolation PRIVATE prtlab_compressors prtlab_core prtlab_warnings)
