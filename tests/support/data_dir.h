// Benchmark data that is not in the repository (the Oxford affine set, the
// real photos): one directory per data set under KG_DATA_DIR. The
// environment variable KG_DATA_DIR, when set, overrides the CMake cache
// variable of the same name (default ../shared/data beside the checkout).
//
// A test that reads a data set starts with KG_REQUIRE_DATA("oxford") and is
// registered with kg_add_test(... NEEDS_DATA <gtest filter> DATA_SET oxford)
// in tests/CMakeLists.txt. CMake registers it only when the set is there at
// configure time (otherwise configuring names it as not run, and why), with
// the ctest label needs-data; .ci/run fails when any of them did not run. A
// registered test whose set is missing when it runs (KG_DATA_DIR pointed
// elsewhere since) fails with the reason: it is never silently skipped.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

namespace kg::test {

inline std::string data_root() {
  const char* env = std::getenv("KG_DATA_DIR");
  return env != nullptr && *env != '\0' ? std::string(env) : std::string(KG_DATA_DIR);
}

// The directory of one data set, e.g. data_dir("oxford").
inline std::string data_dir(const std::string& set) {
  return data_root() + "/" + set;
}

inline bool has_data(const std::string& set) {
  std::error_code ec;
  return std::filesystem::is_directory(data_dir(set), ec);
}

// The failure message; .ci/run looks for its first words.
inline std::string missing_data(const std::string& set) {
  return "needs data: no directory " + data_dir(set) +
         "; set KG_DATA_DIR to the directory that holds " + set +
         "/ (environment, or cmake -DKG_DATA_DIR=...; README: Test data)";
}

}  // namespace kg::test

// Fails and leaves the calling test (a void function: the test body or
// SetUp) when the data set is missing.
#define KG_REQUIRE_DATA(set)                       \
  if (!::kg::test::has_data(set)) {                \
    GTEST_FAIL() << ::kg::test::missing_data(set); \
  }                                                \
  static_assert(true, "a semicolon follows KG_REQUIRE_DATA")
