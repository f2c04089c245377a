# What `cmake --install` puts where. The paths follow the install prefix, also one given at
# install time (`cmake --install build --prefix /opt/hapticd`): the systemd unit is generated
# then, by cmake/install_unit.cmake, so its ExecStart names the binary that was installed.
# The binary is stripped (its debug information stays in the build tree).

install(CODE "set(CMAKE_INSTALL_DO_STRIP ON)")  # before the targets: they honour it
install(TARGETS hapticd hapticctl RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# /usr installs its configuration in /etc (the FHS), every other prefix in PREFIX/etc.
if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  set(HAPTICD_CONFIG_DESTINATION /etc/hapticd)
else()
  set(HAPTICD_CONFIG_DESTINATION ${CMAKE_INSTALL_SYSCONFDIR}/hapticd)
endif()
install(FILES ${PROJECT_SOURCE_DIR}/config/sim.yaml DESTINATION ${HAPTICD_CONFIG_DESTINATION}
        RENAME hapticd.yaml)
install(FILES ${PROJECT_SOURCE_DIR}/docs/man/hapticd.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)

# Where systemd looks for units under this prefix, as pkg-config's systemdsystemunitdir
# says (relative to the prefix, so it follows --prefix too).
execute_process(
  COMMAND ${PKG_CONFIG_EXECUTABLE} --define-variable=rootprefix=/@prefix@
          --define-variable=prefix=/@prefix@ --variable=systemdsystemunitdir systemd
  OUTPUT_VARIABLE _unit_dir OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE _unit_rc)
if(NOT _unit_rc EQUAL 0 OR NOT _unit_dir MATCHES "^/@prefix@/")
  set(_unit_dir "/@prefix@/lib/systemd/system")
endif()
string(REPLACE "/@prefix@/" "" _unit_dir "${_unit_dir}")
set(HAPTICD_SYSTEMD_UNIT_DIR "${_unit_dir}" CACHE STRING
    "systemd system unit directory, relative to the install prefix unless absolute")
install(CODE "
  set(HAPTICD_UNIT_TEMPLATE \"${PROJECT_SOURCE_DIR}/systemd/hapticd.service.in\")
  set(HAPTICD_UNIT_DIR \"${HAPTICD_SYSTEMD_UNIT_DIR}\")
  set(HAPTICD_INSTALL_BINDIR \"${CMAKE_INSTALL_BINDIR}\")
  set(HAPTICD_INSTALL_SYSCONFDIR \"${CMAKE_INSTALL_SYSCONFDIR}\")
  include(\"${PROJECT_SOURCE_DIR}/cmake/install_unit.cmake\")")
