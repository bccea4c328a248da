// Diagnostic logging of the core: KG_LOG("fmt", args...) prints one line on
// stderr when the core is compiled with KG_CORE_LOG (CMake option, off by
// default) and compiles to nothing otherwise, arguments unevaluated.
#pragma once

#if defined(KG_CORE_LOG)
#include <stdio.h>  // flockfile (POSIX)

#include <cstdio>
// The stream stays locked for the whole line: detectors on several threads
// (the builder's quality report) never interleave their lines.
#define KG_LOG(...)                     \
  do {                                  \
    flockfile(stderr);                  \
    std::fprintf(stderr, "keygraph: "); \
    std::fprintf(stderr, __VA_ARGS__);  \
    std::fputc('\n', stderr);           \
    funlockfile(stderr);                \
  } while (false)
#else
#define KG_LOG(...) \
  do {              \
  } while (false)
#endif
