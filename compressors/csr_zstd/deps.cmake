# zstd (Debian libzstd-dev, listed in packages.txt) for this backend's objects only. pkg-config
# first; a plain library search where libzstd.pc is missing. The imported target is GLOBAL because
# the programs that link the backend's objects live in other directories.
find_package(PkgConfig QUIET)
if(PKG_CONFIG_FOUND)
  pkg_check_modules(PRTLAB_ZSTD QUIET IMPORTED_TARGET GLOBAL libzstd)
endif()
if(TARGET PkgConfig::PRTLAB_ZSTD)
  target_link_libraries(${PRTLAB_BACKEND_TARGET} PRIVATE PkgConfig::PRTLAB_ZSTD)
else()
  find_path(PRTLAB_ZSTD_INCLUDE_DIR zstd.h)
  find_library(PRTLAB_ZSTD_LIBRARY NAMES zstd)
  if(NOT PRTLAB_ZSTD_INCLUDE_DIR OR NOT PRTLAB_ZSTD_LIBRARY)
    message(FATAL_ERROR "${PRTLAB_BACKEND_DIR}: zstd not found; install libzstd-dev (scripts/setup.sh does)")
  endif()
  target_include_directories(${PRTLAB_BACKEND_TARGET} PRIVATE ${PRTLAB_ZSTD_INCLUDE_DIR})
  target_link_libraries(${PRTLAB_BACKEND_TARGET} PRIVATE ${PRTLAB_ZSTD_LIBRARY})
endif()
