# Runs at install time (cmake/install.cmake): writes the systemd template unit
# hapticd@.service for the prefix being installed to, under DESTDIR when one is set, and
# installs the default instance's configuration where that unit reads it.
set(_prefix "${CMAKE_INSTALL_PREFIX}")
set(HAPTICD_BINDIR "${_prefix}/${HAPTICD_INSTALL_BINDIR}")
if(_prefix STREQUAL "/usr")
  set(HAPTICD_CONFIG_DIR "/etc/hapticd")
else()
  set(HAPTICD_CONFIG_DIR "${_prefix}/${HAPTICD_INSTALL_SYSCONFDIR}/hapticd")
endif()
if(IS_ABSOLUTE "${HAPTICD_UNIT_DIR}")
  set(_dir "${HAPTICD_UNIT_DIR}")
else()
  set(_dir "${_prefix}/${HAPTICD_UNIT_DIR}")
endif()
set(_out "$ENV{DESTDIR}${_dir}/hapticd@.service")
message(STATUS "Installing: ${_out}")
configure_file("${HAPTICD_UNIT_TEMPLATE}" "${_out}" @ONLY)
# file(INSTALL) puts DESTDIR in front of the destination itself.
file(INSTALL "${HAPTICD_DEFAULT_CONFIG}" DESTINATION "${HAPTICD_CONFIG_DIR}" RENAME hapticd.yaml)
