# Install layout and the build tree's data directory (docs/deploy.md).
#
#   bin/                       palp-server, palp-client, palp-review, palp-recorder, tools
#   lib/libpalp.a              the model library; lib/palp/ the example device driver
#   include/palp/              palp.h (model API), input.h (device-driver interface)
#   lib/pkgconfig/palp.pc      pkg-config (relocatable: prefix from ${pcfiledir})
#   lib/cmake/palp/            palpConfig.cmake: imported target palp::palp
#   share/palp/config/         server.json (installed variant), scenes, params, DDS configs
#   share/palp/db/migrations/  the session-log schema (also compiled into the programs)
#   share/palp/systemd/        unit files (also lib/systemd/system/)
#   share/doc/palp/            README, docs, the device-driver example source
#   var/lib/palp/              the installed server.json's session database
#
# Programs locate share/palp from their own path (app/palp_app.h), so the whole
# prefix can be moved (or installed with DESTDIR) and still works.
include(GNUInstallDirs)

# build/share/palp: what the programs in build/ use as their data directory. A
# link to the source tree's config/ (edits show at once, as before) and a marker
# that tells palp_app_data_dir this is a build tree.
function(palp_build_tree_data_dir)
  set(d ${CMAKE_BINARY_DIR}/share/palp)
  file(MAKE_DIRECTORY ${d}/db)
  file(CREATE_LINK ${CMAKE_SOURCE_DIR}/config ${d}/config SYMBOLIC)
  file(CREATE_LINK ${CMAKE_SOURCE_DIR}/db/migrations ${d}/db/migrations SYMBOLIC)
  file(CREATE_LINK ${CMAKE_SOURCE_DIR}/web/www ${d}/www SYMBOLIC)
  file(WRITE ${d}/palp-build-tree "palp build tree: config/ is the source tree's\n")
endfunction()

function(palp_install_rules)
  set(PALP_PROGRAMS palp-server palp-client palp-review palp-recorder palp-run palp-stats palp-fem palp-eval
      palp-sweep palp-web palp-netem)
  install(TARGETS ${PALP_PROGRAMS} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

  # The model library and its headers. Static: the model's step is inlined and
  # vectorised at -O3, and a static archive keeps a trainee station one file.
  install(TARGETS palp ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(FILES ${CMAKE_SOURCE_DIR}/src/palp.h ${CMAKE_SOURCE_DIR}/client/input.h
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/palp)
  install(TARGETS palp_device_example LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/palp)

  # pkg-config and CMake package files, both relocatable.
  set(pcdir ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
  file(RELATIVE_PATH PALP_PC_TO_PREFIX /${pcdir} /)
  set(cmdir ${CMAKE_INSTALL_LIBDIR}/cmake/palp)
  file(RELATIVE_PATH PALP_CMAKE_TO_PREFIX /${cmdir} /)
  configure_file(${CMAKE_SOURCE_DIR}/cmake/palp.pc.in ${CMAKE_BINARY_DIR}/install/palp.pc @ONLY)
  configure_file(${CMAKE_SOURCE_DIR}/cmake/palpConfig.cmake.in ${CMAKE_BINARY_DIR}/install/palpConfig.cmake @ONLY)
  include(CMakePackageConfigHelpers)
  write_basic_package_version_file(${CMAKE_BINARY_DIR}/install/palpConfigVersion.cmake
                                   VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
  install(FILES ${CMAKE_BINARY_DIR}/install/palp.pc DESTINATION ${pcdir})
  install(FILES ${CMAKE_BINARY_DIR}/install/palpConfig.cmake ${CMAKE_BINARY_DIR}/install/palpConfigVersion.cmake
          DESTINATION ${cmdir})

  # Configs. The installed server configs (server.json, server-exercises.json, server-classroom.json,
  # server-paper.json: every config/server*.json) differ from the source tree's in their paths into
  # the source tree's out/: the session database lives under var/lib/palp of the prefix (the systemd
  # unit passes /var/lib/palp explicitly), and server-classroom.json's PKI under etc/palp/certs of the
  # prefix (keys never beside the database: docs/deploy.md). Both relative to the config, so they
  # follow the prefix. Until session 81 only server.json was rewritten, and the others logged into
  # <prefix>/share/palp/out/.
  set(datadir ${CMAKE_INSTALL_DATADIR}/palp)
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/config/ DESTINATION ${datadir}/config
          PATTERN "server*.json" EXCLUDE PATTERN "systemd" EXCLUDE)
  file(RELATIVE_PATH to_state /${datadir}/config /${CMAKE_INSTALL_LOCALSTATEDIR}/lib/palp)
  file(RELATIVE_PATH to_certs /${datadir}/config /${CMAKE_INSTALL_SYSCONFDIR}/palp/certs)
  file(GLOB server_configs RELATIVE ${CMAKE_SOURCE_DIR}/config ${CMAKE_SOURCE_DIR}/config/server*.json)
  foreach(cf ${server_configs}) # re-read at a configure after an edit
    set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/config/${cf})
  endforeach()
  foreach(cf ${server_configs})
    file(READ ${CMAKE_SOURCE_DIR}/config/${cf} json)
    string(REPLACE "\"../out/palp-sessions.db\"" "\"${to_state}/palp-sessions.db\"" json "${json}")
    string(REPLACE "\"../out/pki\"" "\"${to_certs}\"" json "${json}")
    string(REPLACE "bash scripts/make-classroom-pki.sh out/pki classroom"
                   "bash share/palp/scripts/make-classroom-pki.sh etc/palp/certs classroom (under the prefix)" json "${json}")
    if(NOT json MATCHES "\"${to_state}/palp-sessions.db\"" OR json MATCHES "\\.\\./out/")
      message(FATAL_ERROR "config/${cf}: \"database\" is no longer ../out/palp-sessions.db, or another path "
                          "leads into ../out/; update cmake/PalpInstall.cmake")
    endif()
    file(WRITE ${CMAKE_BINARY_DIR}/install/${cf} "${json}")
    install(FILES ${CMAKE_BINARY_DIR}/install/${cf} DESTINATION ${datadir}/config)
  endforeach()
  install(DIRECTORY DESTINATION ${CMAKE_INSTALL_LOCALSTATEDIR}/lib/palp)
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/db/migrations/ DESTINATION ${datadir}/db/migrations)
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/web/www/ DESTINATION ${datadir}/www)
  # The classroom PKI (docs/security.md): a secured classroom needs it where palp is installed,
  # not only in a source tree.
  install(PROGRAMS ${CMAKE_SOURCE_DIR}/scripts/make-classroom-pki.sh DESTINATION ${datadir}/scripts)

  # Service units (docs/deploy.md), under share/palp/systemd and where systemd looks
  # for a prefix's units (lib/systemd/system), with the installed paths filled in.
  configure_file(${CMAKE_SOURCE_DIR}/cmake/install_units.cmake.in ${CMAKE_BINARY_DIR}/install/install_units.cmake @ONLY)
  install(SCRIPT ${CMAKE_BINARY_DIR}/install/install_units.cmake)

  install(FILES ${CMAKE_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/docs)
  install(FILES ${CMAKE_SOURCE_DIR}/client/device_example.c DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples)
endfunction()
