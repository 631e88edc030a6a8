# prtlab as a CMake package, so that code outside this tree (compressor plugins above all, see
# examples/plugin-template and docs/adding-a-compressor.md) can write
#
#   find_package(prtlab REQUIRED)
#   target_link_libraries(my_plugin PRIVATE prtlab::core)
#
# against either an install (cmake --install <build> --prefix <prefix>, then
# -Dprtlab_DIR=<prefix>/lib/cmake/prtlab) or this build tree directly (-Dprtlab_DIR=<build dir>,
# no install step: the build-tree export below points at the sources and the built library).
#
# Exported: prtlab_core as prtlab::core (the shared library libprtlab_core.so that the prtlab
# program itself uses, so that a plugin registers into the program's registries), and prtlab_warnings as prtlab::warnings only because
# prtlab_core names it as a private link dependency (it carries compile options, no library, so
# it adds nothing to a consumer's link). The built-in backends (compressors/) are not exported:
# a plugin brings its own backend and registers it with the same macro they use.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(PRTLAB_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/prtlab)

# Consumers compile prtlab's headers, which need C++20 (std::span, concepts).
target_compile_features(prtlab_core PUBLIC cxx_std_20)
set_target_properties(prtlab_core PROPERTIES EXPORT_NAME core)
set_target_properties(prtlab_warnings PROPERTIES EXPORT_NAME warnings)

install(TARGETS prtlab_core prtlab_warnings EXPORT prtlabTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/core/include/prtlab DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
set_target_properties(prtlab PROPERTIES INSTALL_RPATH "$ORIGIN/../${CMAKE_INSTALL_LIBDIR}")
install(TARGETS prtlab RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/plugin-template
  DESTINATION ${CMAKE_INSTALL_DATADIR}/prtlab/examples)
install(FILES ${PROJECT_SOURCE_DIR}/docs/adding-a-compressor.md
  DESTINATION ${CMAKE_INSTALL_DATADIR}/prtlab/docs)

install(EXPORT prtlabTargets NAMESPACE prtlab:: DESTINATION ${PRTLAB_INSTALL_CMAKEDIR})
export(EXPORT prtlabTargets NAMESPACE prtlab:: FILE ${PROJECT_BINARY_DIR}/prtlabTargets.cmake)

file(STRINGS ${PROJECT_SOURCE_DIR}/core/include/prtlab/compress/plugin.h PRTLAB_API_LINE
  REGEX "kPluginApiVersion = [0-9]+")
string(REGEX REPLACE ".*kPluginApiVersion = ([0-9]+).*" "\\1" PRTLAB_PLUGIN_API_VERSION "${PRTLAB_API_LINE}")
if(NOT PRTLAB_PLUGIN_API_VERSION MATCHES "^[0-9]+$")
  message(FATAL_ERROR "prtlab: cannot read kPluginApiVersion from compress/plugin.h")
endif()

# One config file for both places: it finds prtlabTargets.cmake beside itself.
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/prtlabConfig.cmake.in
  ${PROJECT_BINARY_DIR}/prtlabConfig.cmake
  INSTALL_DESTINATION ${PRTLAB_INSTALL_CMAKEDIR})
# A plugin links a copy of prtlab_core and shares its classes with the host by ABI, so it must
# be built against the prtlab that loads it; SameMinorVersion refuses the obvious mismatches at
# configure time, kPluginApiVersion the rest at load time.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/prtlabConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/prtlabConfig.cmake ${PROJECT_BINARY_DIR}/prtlabConfigVersion.cmake
  DESTINATION ${PRTLAB_INSTALL_CMAKEDIR})
