# Every find_package of the project, imported targets only (STYLE.md section 1).
# All of them are Debian 12 packages installed by scripts/install-deps.sh.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(nanoflann REQUIRED)
find_package(Threads REQUIRED)
find_package(Protobuf REQUIRED)
find_package(ZLIB REQUIRED)
find_package(OpenCASCADE REQUIRED)
# Mesh decimation (analysis/preprocess/decimation.cpp): vtkDecimatePro and the data types it
# needs, nothing more (docs/decimation.md: why VTK, what it costs to install).
find_package(VTK REQUIRED COMPONENTS CommonCore CommonDataModel FiltersCore)
find_package(PkgConfig REQUIRED)
pkg_check_modules(LIBUSB REQUIRED IMPORTED_TARGET libusb-1.0)
pkg_check_modules(LIBMODBUS REQUIRED IMPORTED_TARGET libmodbus)
pkg_check_modules(LIBSYSTEMD REQUIRED IMPORTED_TARGET libsystemd)
pkg_check_modules(LIBMOSQUITTO REQUIRED IMPORTED_TARGET libmosquitto)
pkg_check_modules(ARAVIS REQUIRED IMPORTED_TARGET aravis-0.8)  # GenICam cameras (drivers/genicam/)
# springscand's operator page (daemon/page_server.cpp; docs/operator-page.md: why civetweb).
# Debian 12's libcivetweb-dev has no .pc file, and its CMake config fails on an executable of
# another package (/usr/bin/civetweb): the imported target is made here from the header and
# library.
find_path(SPRINGSCAN_CIVETWEB_INCLUDE_DIR civetweb.h REQUIRED)
find_library(SPRINGSCAN_CIVETWEB_LIBRARY civetweb REQUIRED)
add_library(civetweb::civetweb UNKNOWN IMPORTED)
set_target_properties(civetweb::civetweb PROPERTIES
  IMPORTED_LOCATION "${SPRINGSCAN_CIVETWEB_LIBRARY}"
  INTERFACE_INCLUDE_DIRECTORIES "${SPRINGSCAN_CIVETWEB_INCLUDE_DIR}")
if(SPRINGSCAN_BUILD_TESTS)
  find_package(GTest REQUIRED)
  include(GoogleTest)
endif()
# umockdev presents the scanner simulator to libusb as a USB device (simulators/, driver tests).
if(SPRINGSCAN_BUILD_TESTS OR SPRINGSCAN_BUILD_SIMULATORS)
  pkg_check_modules(UMOCKDEV REQUIRED IMPORTED_TARGET umockdev-1.0)
  find_library(SPRINGSCAN_UMOCKDEV_PRELOAD NAMES umockdev-preload REQUIRED)
endif()
if(SPRINGSCAN_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()

# OpenCASCADE's config exports plain library names; collect the ones analysis/cad_*.cpp uses.
set(SPRINGSCAN_OCCT_LIBRARIES
    TKernel TKMath TKG2d TKG3d TKGeomBase TKBRep TKGeomAlgo TKTopAlgo TKPrim TKShHealing
    TKMesh TKBO TKBool TKFillet TKOffset TKXSBase TKIGES TKSTEP TKSTEPBase TKSTEPAttr
    TKSTEP209)
