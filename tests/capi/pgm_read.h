/* A binary PGM (P5, maxval 255) reader in C99 for the C API's test
 * programs, which have no image library. */
#ifndef KG_TESTS_CAPI_PGM_READ_H
#define KG_TESTS_CAPI_PGM_READ_H

#include <stdint.h>

typedef struct pgm_image {
  uint8_t* pixels; /* width * height bytes, rows packed; free() it */
  int width;
  int height;
} pgm_image;

/* Reads `path` into `out`; 0 on success, else -1 with a message on stderr. */
int pgm_read(const char* path, pgm_image* out);

#endif
