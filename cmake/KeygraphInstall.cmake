# install(): static libraries, public headers, the CLI, a CMake package with
# one component per library and a pkg-config file per library.
#
#   component  CMake target         pkg-config          brings along
#   core       keygraph::core       keygraph            nothing (libkeygraph_core.a)
#   capi       keygraph::capi       keygraph-c          core; the C API (keygraph/keygraph.h)
#   platform   keygraph::platform   keygraph-platform   core
#   files      keygraph::files      keygraph-files      platform; OpenCV imgcodecs when built with it
#   v4l2       keygraph::v4l2       keygraph-v4l2       platform
#   libcamera  keygraph::libcamera  keygraph-libcamera  platform, libcamera
#
# Each component's dependencies are looked for only when it is asked for
# (cmake/keygraphConfig.cmake.in), so find_package(keygraph COMPONENTS core)
# needs neither OpenCV nor libcamera. The desktop model builder and the
# evaluation are not installed: their C++ interfaces are internal (cv::Mat,
# model records); `keygraph build` makes indexes.
include(CMakePackageConfigHelpers)

# Two install components, one Debian package each (cmake/KeygraphPackage.cmake):
#   dev   libraries, headers, CMake package, pkg-config files, licence
#   tool  the keygraph command-line tool, with its own export file, so that
#         the CMake package works whether or not the tool is installed
set(_kg_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/keygraph)
set(_kg_pc_dir ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# The .pc files locate the prefix from their own directory (${pcfiledir}),
# so `cmake --install --prefix DIR` and a copied install tree both work.
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

# kg_install_component(COMPONENT TARGET PC_NAME DESCRIPTION [REQUIRES pc...]
#                      [LIBS flag...]): the library with its own export file
# (keygraph<Component>Targets.cmake), its public headers (platform/) and its
# pkg-config file, whose Libs line ends with LIBS.
function(kg_install_component component target pc_name description)
  cmake_parse_arguments(ARG "" "" "REQUIRES;LIBS" ${ARGN})
  string(SUBSTRING ${component} 0 1 _first)
  string(SUBSTRING ${component} 1 -1 _rest)
  string(TOUPPER ${_first} _first)
  set(_export keygraph${_first}${_rest}Targets)
  install(TARGETS ${target} EXPORT ${_export}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
  install(EXPORT ${_export} NAMESPACE keygraph:: DESTINATION ${_kg_cmake_dir} COMPONENT dev)
  get_target_property(_headers ${target} KG_PUBLIC_HEADERS)
  if(_headers)
    foreach(_header IN LISTS _headers)
      get_filename_component(_dir ${_header} DIRECTORY)
      install(FILES ${PROJECT_SOURCE_DIR}/platform/${_header}
              DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/keygraph/platform/${_dir} COMPONENT dev)
    endforeach()
  endif()
  get_target_property(_output ${target} OUTPUT_NAME)
  if(NOT _output)
    set(_output ${target})
  endif()
  set(KG_PC_NAME ${pc_name})
  set(KG_PC_DESCRIPTION "${description}")
  set(KG_PC_LIB ${_output})
  set(KG_PC_EXTRA_LIBS "")
  if(ARG_LIBS)
    list(JOIN ARG_LIBS " " _libs)
    set(KG_PC_EXTRA_LIBS " ${_libs}")
  endif()
  # Requires, not Requires.private: the libraries are static, so a
  # consumer links what they link.
  set(KG_PC_REQUIRES_LINE "")
  if(ARG_REQUIRES)
    list(JOIN ARG_REQUIRES ", " _requires)
    set(KG_PC_REQUIRES_LINE "Requires: ${_requires}")
  endif()
  configure_file(${PROJECT_SOURCE_DIR}/cmake/keygraph.pc.in ${PROJECT_BINARY_DIR}/pkgconfig/${pc_name}.pc
                 @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/pkgconfig/${pc_name}.pc DESTINATION ${_kg_pc_dir} COMPONENT dev)
endfunction()

set(KG_INSTALLED_COMPONENTS core)
kg_install_component(core keygraph_core keygraph "Planar object detection with keygraphs (runtime core)")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/keygraph DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        COMPONENT dev)
# The C API: C programs link with a C driver, which adds no C++ runtime,
# so its .pc names it, after the core (the core's leaves it to the C++
# driver). The core's library is named here rather than required through
# keygraph.pc, which would put it after the runtime.
list(APPEND KG_INSTALLED_COMPONENTS capi)
kg_install_component(capi keygraph_capi keygraph-c "keygraph's C API (keygraph/keygraph.h)"
                     LIBS -lkeygraph_core -lstdc++ -lm)
if(TARGET keygraph_platform)
  list(APPEND KG_INSTALLED_COMPONENTS platform)
  kg_install_component(platform keygraph_platform keygraph-platform
                       "keygraph frame sources: the FrameSource interface, pixel-format conversions"
                       REQUIRES keygraph)
  # The file source decodes non-PGM images with OpenCV when built with it:
  # then it links OpenCV's imgcodecs (opencv4.pc on Debian).
  set(_kg_files_requires keygraph-platform)
  if(KG_FILES_HAVE_OPENCV)
    list(APPEND _kg_files_requires opencv4)
  endif()
  kg_install_component(files keygraph_platform_files keygraph-files
                       "keygraph frame source: image files" REQUIRES ${_kg_files_requires})
  list(APPEND KG_INSTALLED_COMPONENTS files)
  if(TARGET keygraph_platform_v4l2)
    kg_install_component(v4l2 keygraph_platform_v4l2 keygraph-v4l2
                         "keygraph frame source: V4L2 cameras" REQUIRES keygraph-platform)
    list(APPEND KG_INSTALLED_COMPONENTS v4l2)
  endif()
  if(TARGET keygraph_platform_libcamera)
    kg_install_component(libcamera keygraph_platform_libcamera keygraph-libcamera
                         "keygraph frame source: libcamera cameras"
                         REQUIRES keygraph-platform libcamera)
    list(APPEND KG_INSTALLED_COMPONENTS libcamera)
  endif()
endif()

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

# The licence, where Debian keeps it: one directory per package, so that the
# two packages never own the same file.
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/libkeygraph-dev
        RENAME copyright COMPONENT dev)
if(TARGET keygraph)
  install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/keygraph
          RENAME copyright COMPONENT tool)
endif()
