# Debian packages with CPack, from any build directory (host or cross):
#   cpack --config <build>/CPackConfig.cmake -B <out>
# gives two .deb files (install components of cmake/KeygraphInstall.cmake):
#   libkeygraph-dev_<version>_<arch>.deb  static libraries (core, frame sources),
#                                         headers, CMake package, pkg-config files
#   keygraph_<version>_<arch>.deb         the keygraph tool (desktop or device)
# <arch> is the build's target: amd64, or arm64 / armhf from the cross
# toolchains. Both install under /usr. The tool's dependencies come from
# dpkg-shlibdeps (the target's libraries must be installed, through
# multiarch for cross-builds: .ci/install-deps --cross).

execute_process(COMMAND dpkg-architecture -t ${CMAKE_LIBRARY_ARCHITECTURE} -qDEB_HOST_ARCH
                OUTPUT_VARIABLE _kg_deb_arch OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT _kg_deb_arch)
  message(STATUS "keygraph: no Debian architecture for '${CMAKE_LIBRARY_ARCHITECTURE}' "
                 "(dpkg-architecture, from dpkg-dev): no Debian packages")
  return()
endif()

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME keygraph)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
# No CPACK_PACKAGE_DESCRIPTION_SUMMARY: CPack would put it before every
# package's own description; each description's first line is its package's
# short description instead (Debian's Description field).
set(CPACK_RESOURCE_FILE_LICENSE "${PROJECT_SOURCE_DIR}/LICENSE")
set(CPACK_PACKAGE_CONTACT "keygraph maintainers <maintainers@keygraph.invalid>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL dev)
if(TARGET keygraph)
  list(APPEND CPACK_COMPONENTS_ALL tool)
endif()
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # <name>_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE ${_kg_deb_arch})

set(CPACK_DEBIAN_DEV_PACKAGE_NAME libkeygraph-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
# One string each (several strings would be a CMake list, joined by ';'):
# the first line is Debian's short description, the rest the long one.
set(CPACK_COMPONENT_DEV_DESCRIPTION
    "keygraph: static libraries and headers\n\
The runtime core (C++17, no OpenCV), the frame sources (keygraph/platform/),\n\
the CMake package (find_package(keygraph COMPONENTS core files v4l2 ...)) and\n\
the pkg-config files (keygraph.pc, keygraph-files.pc, ...). Each component\n\
needs only its own dependencies: the core none.")
# What a component needs is suggested, not required: the core alone needs
# nothing; keygraph::files needs OpenCV's imgcodecs when it was built with
# them, keygraph::libcamera libcamera through pkg-config
# (cmake/keygraphConfig.cmake.in says so when one is missing).
set(_kg_dev_suggests pkg-config)
if(KG_FILES_HAVE_OPENCV)
  list(APPEND _kg_dev_suggests libopencv-dev)
endif()
if(TARGET keygraph_platform_libcamera)
  list(APPEND _kg_dev_suggests libcamera-dev)
endif()
list(JOIN _kg_dev_suggests ", " CPACK_DEBIAN_DEV_PACKAGE_SUGGESTS)

set(CPACK_DEBIAN_TOOL_PACKAGE_NAME keygraph)
set(CPACK_DEBIAN_TOOL_PACKAGE_SECTION graphics)
if(KG_BUILD_TOOLS)
  set(CPACK_COMPONENT_TOOL_DESCRIPTION
      "keygraph: build, detect, evaluate and run live detection\n\
The desktop keygraph tool: builds model indexes (OpenCV), detects, inspects,\n\
evaluates, and detects live on cameras and image files.")
  # keygraph demo reads box.png and box_in_scene.png from opencv-doc.
  set(CPACK_DEBIAN_TOOL_PACKAGE_RECOMMENDS opencv-doc)
else()
  set(CPACK_COMPONENT_TOOL_DESCRIPTION
      "keygraph: live detection on a device\n\
The device build of the keygraph tool (no OpenCV): live detection on V4L2\n\
and libcamera cameras and image files, bench, inspect, detect on PGM files.")
endif()
# libcamera finds a camera's pipeline through its IPA modules (Debian:
# libcamera-ipa, which libcamera0.0.3 does not pull in).
if(TARGET keygraph_platform_libcamera)
  list(APPEND CPACK_DEBIAN_TOOL_PACKAGE_RECOMMENDS libcamera-ipa)
endif()
string(REPLACE ";" ", " CPACK_DEBIAN_TOOL_PACKAGE_RECOMMENDS "${CPACK_DEBIAN_TOOL_PACKAGE_RECOMMENDS}")
# dpkg-shlibdeps needs the target's libraries as Debian packages; a cross
# toolchain alone has them only under /usr/<triple>.
if(NOT CMAKE_CROSSCOMPILING OR EXISTS /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/libc.so.6)
  set(CPACK_DEBIAN_TOOL_PACKAGE_SHLIBDEPS ON)
else()
  set(CPACK_DEBIAN_TOOL_PACKAGE_DEPENDS "libc6 (>= 2.35), libstdc++6 (>= 12), libgcc-s1 (>= 3.0)")
  if(TARGET keygraph_platform_libcamera)
    string(APPEND CPACK_DEBIAN_TOOL_PACKAGE_DEPENDS ", libcamera0.0.3")
  endif()
endif()

include(CPack)
