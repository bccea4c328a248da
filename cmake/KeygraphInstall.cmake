# install(): static libraries, public headers, the CLI, an exported CMake
# package (find_package(keygraph) -> keygraph::core and the frame sources)
# and a pkg-config file for the core. The desktop builder and the evaluation
# are not installed: their C++ interfaces are internal (cv::Mat, model
# records); `keygraph build` is the way to make an index.
include(CMakePackageConfigHelpers)

# Two install components, one Debian package each (cmake/KeygraphPackage.cmake):
#   dev   libraries, headers, CMake package, pkg-config file
#   tool  the keygraph command-line tool, with its own export file, so that
#         the CMake package works whether or not the tool is installed
set(_kg_targets keygraph_core)
# Frame sources (platform/): keygraph::platform, ::files, ::v4l2, ::libcamera.
# Their headers go to <includedir>/keygraph/platform/ and are included as
# "platform/..." (platform/CMakeLists.txt puts <includedir>/keygraph on their
# include path).
set(KG_INSTALLED_PLATFORM "")
foreach(_kg_lib IN ITEMS platform platform_files platform_v4l2 platform_libcamera)
  if(TARGET keygraph_${_kg_lib})
    list(APPEND _kg_targets keygraph_${_kg_lib})
    string(REPLACE "platform_" "" _kg_export ${_kg_lib})
    list(APPEND KG_INSTALLED_PLATFORM ${_kg_export})
  endif()
endforeach()
if(KG_INSTALLED_PLATFORM)
  set(_kg_skip "")  # headers of the sources this build does not have
  foreach(_kg_source IN ITEMS files v4l2 libcamera)
    if(NOT TARGET keygraph_platform_${_kg_source})
      list(APPEND _kg_skip PATTERN ${_kg_source} EXCLUDE)
    endif()
  endforeach()
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/platform/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/keygraph/platform
          COMPONENT dev FILES_MATCHING PATTERN "*.h" ${_kg_skip})
endif()

install(TARGETS ${_kg_targets}
  EXPORT keygraphTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/keygraph DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        COMPONENT dev)

set(_kg_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/keygraph)
install(EXPORT keygraphTargets NAMESPACE keygraph:: DESTINATION ${_kg_cmake_dir} COMPONENT dev)
if(TARGET keygraph)  # desktop or device build of the CLI: keygraph::keygraph
  install(TARGETS keygraph EXPORT keygraphToolTargets RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
          COMPONENT tool)
  install(EXPORT keygraphToolTargets NAMESPACE keygraph:: DESTINATION ${_kg_cmake_dir} COMPONENT tool)
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/keygraphConfig.cmake.in
  ${PROJECT_BINARY_DIR}/keygraphConfig.cmake INSTALL_DESTINATION ${_kg_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/keygraphConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/keygraphConfig.cmake ${PROJECT_BINARY_DIR}/keygraphConfigVersion.cmake
  DESTINATION ${_kg_cmake_dir} COMPONENT dev)

# The .pc file locates the prefix from its own directory (${pcfiledir}), so
# `cmake --install --prefix DIR` and a copied install tree both work.
set(_kg_pc_dir ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}" OR IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(KG_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
else()
  file(RELATIVE_PATH _kg_pc_up "/kg-prefix/${_kg_pc_dir}" "/kg-prefix")
  set(KG_PC_PREFIX "\${pcfiledir}/${_kg_pc_up}")
endif()
set(KG_PC_LIBDIR "${CMAKE_INSTALL_LIBDIR}")
set(KG_PC_INCLUDEDIR "${CMAKE_INSTALL_INCLUDEDIR}")
foreach(_kg_dir IN ITEMS LIBDIR INCLUDEDIR)
  if(NOT IS_ABSOLUTE "${KG_PC_${_kg_dir}}")
    set(KG_PC_${_kg_dir} "\${prefix}/${KG_PC_${_kg_dir}}")
  endif()
endforeach()
configure_file(${PROJECT_SOURCE_DIR}/cmake/keygraph.pc.in ${PROJECT_BINARY_DIR}/keygraph.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/keygraph.pc DESTINATION ${_kg_pc_dir} COMPONENT dev)
