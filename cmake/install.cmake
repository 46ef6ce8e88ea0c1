# `cmake --install build --prefix P` (GNUInstallDirs layout; docs/install.md):
#   P/bin/scoopsim                              the command line
#   P/lib/libdem.a, libarm.a, libsim_*.a        the DEM, the arm and sim's four rooms
#   P/include/scoopsim/{dem,arm,sim/*}/*.h      their public headers (not internal_*.h)
#   P/lib/cmake/scoopsim/                       the package config: find_package(scoopsim)
#   P/share/scoopsim/{scenes,assets,tools}      scenes, the URDF, meshes and lookup CSV, the
#                                               plotting and report scripts
# The Python module (python/) installs itself. Install a release build: the libraries are
# static and a sanitizer build's would need -fsanitize in every user's link.
include(CMakePackageConfigHelpers)

set(SCOOPSIM_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/scoopsim)
set(SCOOPSIM_DATA_DIR ${CMAKE_INSTALL_DATADIR}/scoopsim)

install(TARGETS scoopsim RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# One export per part, so that find_package(scoopsim COMPONENTS dem) looks for OpenMP alone and
# COMPONENTS arm for Eigen, Bullet and urdfdom alone (cmake/scoopsimConfig.cmake.in).
install(TARGETS dem EXPORT scoopsim-dem ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS arm EXPORT scoopsim-arm ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS sim_input sim_files sim_loop sim_studies sim EXPORT scoopsim-sim
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
foreach(part dem arm sim)
  install(EXPORT scoopsim-${part} NAMESPACE scoopsim:: DESTINATION ${SCOOPSIM_CMAKE_DIR}
    FILE scoopsim-${part}-targets.cmake)
endforeach()

# Headers: every .h of dem/, arm/ and sim/'s rooms but the internal ones (internal_*.h, and
# sim/input/yaml_input.h, which includes yaml-cpp and is sim's own).
foreach(folder dem arm sim)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${folder}/
    DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/scoopsim/${folder}
    FILES_MATCHING PATTERN "*.h" PATTERN "internal_*" EXCLUDE PATTERN "yaml_input.h" EXCLUDE)
endforeach()

# Scenes keep their relative paths (materials.yaml, ../assets/scoop.stl) in share/scoopsim.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/scenes ${PROJECT_SOURCE_DIR}/assets
  DESTINATION ${SCOOPSIM_DATA_DIR} PATTERN ".law_*" EXCLUDE)
# The scripts a user runs on a run's files (shebang `#!/usr/bin/env python3`: any python3 with
# numpy, h5py and matplotlib), and the modules they import. report.sh runs them from
# share/scoopsim as it does from the source tree.
install(PROGRAMS
  ${PROJECT_SOURCE_DIR}/tools/plot_wrench.py
  ${PROJECT_SOURCE_DIR}/tools/plot_balovnev.py
  ${PROJECT_SOURCE_DIR}/tools/plot_fault_timeline.py
  ${PROJECT_SOURCE_DIR}/tools/plot_lookup.py
  ${PROJECT_SOURCE_DIR}/tools/plot_size_study.py
  ${PROJECT_SOURCE_DIR}/tools/plot_testbed.py
  ${PROJECT_SOURCE_DIR}/tools/fz_by_pass.py
  ${PROJECT_SOURCE_DIR}/tools/tile_bed.py
  ${PROJECT_SOURCE_DIR}/tools/table_accuracy.py
  ${PROJECT_SOURCE_DIR}/tools/report.py
  ${PROJECT_SOURCE_DIR}/tools/report.sh
  DESTINATION ${SCOOPSIM_DATA_DIR}/tools)
install(FILES ${PROJECT_SOURCE_DIR}/tools/study_csv.py DESTINATION ${SCOOPSIM_DATA_DIR}/tools)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/scoopsimConfig.cmake.in
  ${PROJECT_BINARY_DIR}/scoopsimConfig.cmake INSTALL_DESTINATION ${SCOOPSIM_CMAKE_DIR}
  PATH_VARS SCOOPSIM_DATA_DIR)
# 0.x: a minor version may change the API.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/scoopsimConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/scoopsimConfig.cmake
  ${PROJECT_BINARY_DIR}/scoopsimConfigVersion.cmake DESTINATION ${SCOOPSIM_CMAKE_DIR})
