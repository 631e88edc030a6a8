# prtlab_embed_kernels(KERNEL_DIR <dir> OUTPUT <file.cpp>)
#
# Embeds every <dir>/*.cl into a generated C++ source (raw string literals, one per file, plus
# a sorted name -> source table read by core/src/opencl/cl_kernel_sources.cpp). The glob is
# CONFIGURE_DEPENDS, so adding or removing a .cl file re-runs CMake; the list of names is part
# of the command line, so that change also regenerates the file; editing a .cl file re-runs
# only this command (DEPENDS), then recompiles one .cpp.
set(PRTLAB_EMBED_KERNELS_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/embed_kernels.cmake)

function(prtlab_embed_kernels)
  cmake_parse_arguments(ARG "" "KERNEL_DIR;OUTPUT" "" ${ARGN})
  if(NOT ARG_KERNEL_DIR OR NOT ARG_OUTPUT)
    message(FATAL_ERROR "prtlab_embed_kernels: KERNEL_DIR and OUTPUT are required")
  endif()
  file(GLOB kernels CONFIGURE_DEPENDS ${ARG_KERNEL_DIR}/*.cl)
  list(SORT kernels)
  set(names "")
  foreach(k IN LISTS kernels)
    get_filename_component(n ${k} NAME_WLE)
    string(APPEND names "${n},")
  endforeach()
  add_custom_command(
    OUTPUT ${ARG_OUTPUT}
    COMMAND ${CMAKE_COMMAND} -DKERNEL_DIR=${ARG_KERNEL_DIR} -DOUTPUT=${ARG_OUTPUT}
            -DNAMES=${names} -P ${PRTLAB_EMBED_KERNELS_SCRIPT}
    DEPENDS ${kernels} ${PRTLAB_EMBED_KERNELS_SCRIPT}
    COMMENT "prtlab: embedding OpenCL kernels (${names})"
    VERBATIM)
endfunction()
