# bindings_install (tests/capi/install_bindings.sh): the installed C API
# through pkg-config and find_package, and the installed Python and Java
# bindings, on the bindings' scenes. Included by tests/CMakeLists.txt after
# tests/java and tests/python, whose programs it runs.
if(NOT KG_BINDINGS_SCENES OR KG_SANITIZE OR KG_BUILD_FUZZERS)
  # (sanitized builds: see tests/CMakeLists.txt, add_subdirectory(install))
  return()
endif()
set(_kg_python "")
if(TARGET keygraph_python AND KG_PYTHON_TEST_INTERPRETER)
  set(_kg_python ${KG_PYTHON_TEST_INTERPRETER})
endif()
set(_kg_java "")
set(_kg_test_jar "")
if(TARGET keygraph_java_tests)
  set(_kg_java ${Java_JAVA_EXECUTABLE})
  get_target_property(_kg_test_jar keygraph_java_tests JAR_FILE)
endif()
add_test(NAME bindings_install
         COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/install_bindings.sh ${PROJECT_BINARY_DIR} ${PROJECT_SOURCE_DIR}
                 ${CMAKE_COMMAND} ${CMAKE_C_COMPILER} ${KG_BINDINGS_SCENES} "${_kg_python}" "${_kg_java}"
                 "${_kg_test_jar}" "${CMAKE_GENERATOR}" "${CMAKE_MAKE_PROGRAM}")
set_tests_properties(bindings_install PROPERTIES FIXTURES_REQUIRED bindings_scenes TIMEOUT 600
                     # installs the build tree, as install_consume and the cpack of
                     # install_debian_packages do: one at a time
                     RESOURCE_LOCK build_tree_install)
