# What a plant installs (scripts/package.sh builds it as a .deb with CPack): the programs,
# the systemd unit, the udev rule, the commented default config, the demo part it names, and
# the documentation. With CMAKE_INSTALL_PREFIX=/usr (the package), the config goes to /etc and
# the unit and the rule to /lib as Debian 12 packages ship them; with another prefix (a local
# `cmake --install`), everything stays below the prefix.
include(GNUInstallDirs)

if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  set(_springscan_lib_root "/lib")
else()
  set(_springscan_lib_root "${CMAKE_INSTALL_LIBDIR}")
endif()
set(SPRINGSCAN_SYSTEMD_UNIT_DIR "${_springscan_lib_root}/systemd/system" CACHE STRING
    "Where the systemd unit is installed")
set(SPRINGSCAN_UDEV_RULES_DIR "${_springscan_lib_root}/udev/rules.d" CACHE STRING
    "Where the udev rule is installed")

install(TARGETS springscand springscan RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# springscan execs it from ../lib/springscan/ relative to itself (cli/commands.hpp): a private
# program, where Debian puts them (/usr/lib/<package>), not on PATH.
install(TARGETS springscan-commands RUNTIME DESTINATION lib/springscan)
install(FILES config/springscand.textproto
        DESTINATION ${CMAKE_INSTALL_FULL_SYSCONFDIR}/springscan)
install(FILES config/springscand.service DESTINATION ${SPRINGSCAN_SYSTEMD_UNIT_DIR})
install(FILES config/99-springscan.rules DESTINATION ${SPRINGSCAN_UDEV_RULES_DIR})
# The demo part the default config names, so the installed config passes --check as it is.
install(FILES demo/hat-profile.step demo/hat-profile-scan.ply demo/README.md
        DESTINATION ${CMAKE_INSTALL_DATADIR}/springscan/demo)
install(FILES README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR} FILES_MATCHING PATTERN "*.md")
install(FILES packaging/copyright DESTINATION ${CMAKE_INSTALL_DOCDIR})

# The Debian package (cpack -G DEB; scripts/package.sh).
set(CPACK_GENERATOR "DEB")
set(CPACK_PACKAGE_NAME "springscan")
set(CPACK_PACKAGE_VENDOR "springscan")
set(CPACK_PACKAGE_CONTACT "springscan maintainers <springscan@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "press-line inspection station: scan-to-CAD deviation, springback, Modbus TCP to the PLC")
set(CPACK_PACKAGE_DESCRIPTION
    "springscand serves Modbus TCP to the press line's PLC, drives the USB scanner and analyses\n"
    "each part against its CAD model (deviation, springback per bend, compensation vectors).\n"
    "springscan is the command-line analysis. The register map is in\n"
    "/usr/share/doc/springscan/modbus-register-map.md.")
string(REPLACE ";" "" CPACK_PACKAGE_DESCRIPTION "${CPACK_PACKAGE_DESCRIPTION}")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION "misc")
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "adduser, systemd")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    "${PROJECT_SOURCE_DIR}/packaging/conffiles;${PROJECT_SOURCE_DIR}/packaging/postinst;${PROJECT_SOURCE_DIR}/packaging/postrm")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_STRIP_FILES ON)
include(CPack)
