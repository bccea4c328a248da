# The layer rules of docs/ARCHITECTURE.md, checked by the build: what each
# target may link (here, when configuring) and what each layer's files may
# include (cmake/check_layers.cmake, on every build: target kg_layers).

# kg_forbid_links(TARGET FORBIDDEN...): TARGET links none of FORBIDDEN.
function(kg_forbid_links target)
  if(NOT TARGET ${target})
    return()
  endif()
  get_target_property(_links ${target} LINK_LIBRARIES)
  get_target_property(_interface ${target} INTERFACE_LINK_LIBRARIES)
  foreach(_link IN LISTS _links _interface)
    foreach(_forbidden IN LISTS ARGN)
      if(_link MATCHES "${_forbidden}")
        message(FATAL_ERROR "keygraph layer rules (docs/ARCHITECTURE.md): ${target} links "
                            "${_link}, which its layer may not use")
      endif()
    endforeach()
  endforeach()
endfunction()

# The core links nothing but the C++ standard library: Eigen is header-only
# and private to its build.
get_target_property(_kg_core_links keygraph_core LINK_LIBRARIES)
foreach(_link IN LISTS _kg_core_links)
  if(NOT _link MATCHES "Eigen3::Eigen")
    message(FATAL_ERROR "keygraph layer rules (docs/ARCHITECTURE.md): keygraph_core links "
                        "${_link}; the core may link nothing but the C++ standard library")
  endif()
endforeach()
get_target_property(_kg_core_interface keygraph_core INTERFACE_LINK_LIBRARIES)
if(_kg_core_interface)
  foreach(_link IN LISTS _kg_core_interface)
    if(NOT _link MATCHES "Eigen3::Eigen")
      message(FATAL_ERROR "keygraph layer rules: keygraph_core passes ${_link} on to its users")
    endif()
  endforeach()
endif()
foreach(_kg_platform IN ITEMS keygraph_platform keygraph_platform_files keygraph_platform_v4l2
                              keygraph_platform_libcamera)
  kg_forbid_links(${_kg_platform} "keygraph_(builder|eval|cli)" "opencv_(imgproc|features2d|calib3d)")
endforeach()
kg_forbid_links(keygraph_capi "keygraph_(builder|eval|cli|platform)" "opencv")
kg_forbid_links(keygraph_jni "keygraph_(builder|eval|cli|platform)" "opencv")
kg_forbid_links(keygraph_builder "keygraph_(eval|cli)")
kg_forbid_links(keygraph_eval "keygraph_cli")

add_custom_target(kg_layers ALL
  COMMAND ${CMAKE_COMMAND} -DROOT=${PROJECT_SOURCE_DIR} -P ${PROJECT_SOURCE_DIR}/cmake/check_layers.cmake
  COMMENT "Checking the layer rules (docs/ARCHITECTURE.md)" VERBATIM)
