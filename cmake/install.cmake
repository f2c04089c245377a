# What `cmake --install` puts where. The paths follow the install prefix, also one given at
# install time (`cmake --install build --prefix /opt/hapticd`): the systemd unit is generated
# then, by cmake/install_unit.cmake, so its ExecStart names the binary that was installed.
# The binary is stripped (its debug information stays in the build tree).

install(CODE "set(CMAKE_INSTALL_DO_STRIP ON)")  # before the targets: they honour it
install(TARGETS hapticd hapticctl RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The client library applications link (docs/clients.md), its headers and its pkg-config file,
# which is written at install time for the prefix installed to (as the unit is).
install(TARGETS hapticd_client LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(FILES ${PROJECT_SOURCE_DIR}/client/connection.h ${PROJECT_SOURCE_DIR}/client/state_reader.h
              ${PROJECT_SOURCE_DIR}/client/state_layout.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/hapticd/client)
install(CODE "
  set(_pc \"${PROJECT_BINARY_DIR}/hapticd-client.pc\")
  set(PROJECT_VERSION \"${PROJECT_VERSION}\")
  set(CMAKE_INSTALL_LIBDIR \"${CMAKE_INSTALL_LIBDIR}\")
  set(CMAKE_INSTALL_INCLUDEDIR \"${CMAKE_INSTALL_INCLUDEDIR}\")
  configure_file(\"${PROJECT_SOURCE_DIR}/client/hapticd-client.pc.in\" \"\${_pc}\" @ONLY)
  file(INSTALL \"\${_pc}\" DESTINATION \"\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}/pkgconfig\")")

# The default instance's configuration is installed with the unit (cmake/install_unit.cmake):
# /usr installs it in /etc (the FHS), every other prefix in PREFIX/etc, decided for the prefix
# of the install itself, so the unit and the file agree also for `--prefix /usr`.
install(FILES ${PROJECT_SOURCE_DIR}/docs/man/hapticd.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)

# Where systemd looks for units and sysusers.d files under this prefix, as pkg-config says
# (relative to the prefix, so they follow --prefix too); udev rules go to lib/udev/rules.d.
function(hapticd_systemd_dir variable fallback out)
  execute_process(
    COMMAND ${PKG_CONFIG_EXECUTABLE} --define-variable=rootprefix=/@prefix@
            --define-variable=prefix=/@prefix@ --variable=${variable} systemd
    OUTPUT_VARIABLE dir OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0 OR NOT dir MATCHES "^/@prefix@/")
    set(dir "/@prefix@/${fallback}")
  endif()
  string(REPLACE "/@prefix@/" "" dir "${dir}")
  set(${out} "${dir}" PARENT_SCOPE)
endfunction()
hapticd_systemd_dir(systemdsystemunitdir lib/systemd/system _unit_dir)
hapticd_systemd_dir(sysusersdir lib/sysusers.d _sysusers_dir)
set(HAPTICD_SYSTEMD_UNIT_DIR "${_unit_dir}" CACHE STRING
    "systemd system unit directory, relative to the install prefix unless absolute")
set(HAPTICD_SYSUSERS_DIR "${_sysusers_dir}" CACHE STRING
    "sysusers.d directory, relative to the install prefix unless absolute")
set(HAPTICD_UDEV_RULES_DIR "lib/udev/rules.d" CACHE STRING
    "udev rules directory, relative to the install prefix unless absolute")
install(FILES ${PROJECT_SOURCE_DIR}/systemd/hapticd.sysusers DESTINATION ${HAPTICD_SYSUSERS_DIR}
        RENAME hapticd.conf)
# One rule, for /dev/cpu_dma_latency. No device rule is installed: an instance's rules (its CAN
# interface, GPIO chip and PWM channel, HID device) are written from its configuration by
# `hapticd udev-rules` (docs/operations.md lists everything installing changes, and a test
# holds this file to that list).
install(FILES ${PROJECT_SOURCE_DIR}/udev/60-hapticd-rt.rules DESTINATION ${HAPTICD_UDEV_RULES_DIR})
install(CODE "
  set(HAPTICD_UNIT_TEMPLATE \"${PROJECT_SOURCE_DIR}/systemd/hapticd@.service.in\")
  set(HAPTICD_DEFAULT_CONFIG \"${PROJECT_SOURCE_DIR}/config/sim.yaml\")
  set(HAPTICD_UNIT_DIR \"${HAPTICD_SYSTEMD_UNIT_DIR}\")
  set(HAPTICD_INSTALL_BINDIR \"${CMAKE_INSTALL_BINDIR}\")
  set(HAPTICD_INSTALL_SYSCONFDIR \"${CMAKE_INSTALL_SYSCONFDIR}\")
  include(\"${PROJECT_SOURCE_DIR}/cmake/install_unit.cmake\")")
