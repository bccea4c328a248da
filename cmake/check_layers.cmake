# The layer rules of docs/ARCHITECTURE.md, checked on every build (target
# kg_layers) and by ctest (layer_rules): which #include each layer may use.
#   cmake -DROOT=<source dir> -P cmake/check_layers.cmake
# Fails with one line per violation: FILE:LINE: LAYER may not include WHAT.
#
#   include/keygraph   the public contract: keygraph/ headers and the C++
#                      standard library only
#   src/core           core/ and keygraph/ headers, the standard library
#                      and Eigen; no OpenCV, no platform/, builder/, eval/
#                      or cli/
#   platform           platform/ and keygraph/ headers; never src/
#   src/capi           keygraph/ headers and the standard library: the C API
#                      wraps the public contract, never the core's internals
#   src/bindings       the C API (and, for Python's build(), the builder);
#                      never core/, eval/ or cli/
#   src/builder        core/, builder/, platform/files, keygraph/; never
#                      eval/ or cli/
#   src/eval           anything but cli/
#   src/cli            anything
if(NOT ROOT)
  message(FATAL_ERROR "check_layers.cmake: set -DROOT=<source dir>")
endif()

set(_violations "")
# kg_layer(DIR FORBIDDEN_REGEX WHAT): every quoted or angled include in
# DIR's .h/.cpp files matching FORBIDDEN_REGEX is a violation.
function(kg_layer dir forbidden what)
  file(GLOB_RECURSE _files "${ROOT}/${dir}/*.h" "${ROOT}/${dir}/*.cpp")
  foreach(_file IN LISTS _files)
    file(STRINGS "${_file}" _lines REGEX "^[ \t]*#[ \t]*include")
    foreach(_line IN LISTS _lines)
      string(REGEX MATCH "[<\"]([^>\"]+)[>\"]" _m "${_line}")
      set(_target "${CMAKE_MATCH_1}")
      if(_target MATCHES "${forbidden}")
        file(RELATIVE_PATH _rel "${ROOT}" "${_file}")
        list(APPEND _violations "${_rel}: ${dir} may not include ${_target} (${what})")
      endif()
    endforeach()
  endforeach()
  set(_violations "${_violations}" PARENT_SCOPE)
endfunction()

kg_layer(include/keygraph "^(core|builder|eval|cli|platform|opencv2|Eigen)/"
         "the public contract shows no internals")
kg_layer(src/core "^(builder|eval|cli|platform|opencv2)/"
         "the core is the device library: no OpenCV, no desktop layer")
kg_layer(platform "^(core|builder|eval|cli)/|^opencv2/(features2d|calib3d)"
         "frame sources use the public contract only")
kg_layer(src/capi "^(core|builder|eval|cli|platform|opencv2|Eigen)/"
         "the C API wraps the public contract (keygraph/) only")
kg_layer(src/bindings "^(core|eval|cli)/" "the bindings go through the C API (and the builder)")
kg_layer(src/builder "^(eval|cli)/" "the builder is below the evaluation and the CLI")
kg_layer(src/eval "^cli/" "the evaluation is below the CLI")

if(_violations)
  list(LENGTH _violations _n)
  list(JOIN _violations "\n  " _text)
  message(FATAL_ERROR "keygraph layer rules (docs/ARCHITECTURE.md): ${_n} violation(s):\n  ${_text}")
endif()
