// Diagnostic logging of the core: KG_LOG("fmt", args...) prints one line on
// stderr when the core is compiled with KG_CORE_LOG (CMake option, off by
// default) and compiles to nothing otherwise, arguments unevaluated.
#pragma once

#if defined(KG_CORE_LOG)
#include <cstdio>
#define KG_LOG(...)                     \
  do {                                  \
    std::fprintf(stderr, "keygraph: "); \
    std::fprintf(stderr, __VA_ARGS__);  \
    std::fputc('\n', stderr);           \
  } while (false)
#else
#define KG_LOG(...) \
  do {              \
  } while (false)
#endif
