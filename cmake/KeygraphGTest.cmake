# GoogleTest for the test suite: GTest::gtest and GTest::gtest_main.
# Host builds use the installed package (Debian: libgtest-dev). Cross builds
# compile it from source with the target's compiler (Debian's googletest
# package: /usr/src/googletest), since no target copy is installed.
if(CMAKE_CROSSCOMPILING)
  set(KG_GTEST_SOURCE_DIR "/usr/src/googletest" CACHE PATH
      "GoogleTest sources, compiled with the cross compiler for the tests")
  if(NOT EXISTS "${KG_GTEST_SOURCE_DIR}/CMakeLists.txt")
    message(FATAL_ERROR "no GoogleTest sources in ${KG_GTEST_SOURCE_DIR} for the cross-built tests: "
                        "apt-get install googletest, or set KG_GTEST_SOURCE_DIR")
  endif()
  set(BUILD_GMOCK OFF CACHE BOOL "" FORCE)
  set(INSTALL_GTEST OFF CACHE BOOL "" FORCE)
  add_subdirectory(${KG_GTEST_SOURCE_DIR} ${PROJECT_BINARY_DIR}/googletest EXCLUDE_FROM_ALL)
  if(NOT TARGET GTest::gtest OR NOT TARGET GTest::gtest_main)
    message(FATAL_ERROR "${KG_GTEST_SOURCE_DIR} did not define GTest::gtest and GTest::gtest_main")
  endif()
else()
  find_package(GTest REQUIRED)
endif()
