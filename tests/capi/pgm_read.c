/* pgm_read.h: netpbm's pgm(5) for 8-bit samples: "P5", then width, height
 * and maxval as decimals separated by whitespace (with '#' comments), one
 * whitespace byte, then the samples. */
#include "pgm_read.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>

/* The next header number, skipping whitespace and comments; -1 if none. */
static long read_number(FILE* f) {
  int c = fgetc(f);
  long value = 0;
  int digits = 0;
  for (;;) {
    while (c != EOF && isspace(c)) c = fgetc(f);
    if (c != '#') break;
    while (c != EOF && c != '\n') c = fgetc(f);
  }
  while (c != EOF && isdigit(c) && value < 1000000) {
    value = value * 10 + (c - '0');
    ++digits;
    c = fgetc(f);
  }
  /* The single whitespace byte after the number is consumed here. */
  if (digits == 0 || (c != EOF && !isspace(c))) return -1;
  return value;
}

int pgm_read(const char* path, pgm_image* out) {
  FILE* f = fopen(path, "rb");
  long width, height, maxval;
  size_t size;
  out->pixels = NULL;
  out->width = out->height = 0;
  if (f == NULL) {
    fprintf(stderr, "%s: cannot open\n", path);
    return -1;
  }
  if (fgetc(f) != 'P' || fgetc(f) != '5') {
    fprintf(stderr, "%s: not a binary PGM (P5)\n", path);
    fclose(f);
    return -1;
  }
  width = read_number(f);
  height = read_number(f);
  maxval = read_number(f);
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384 || maxval != 255) {
    fprintf(stderr, "%s: unsupported PGM header (8-bit, at most 16384 a side)\n", path);
    fclose(f);
    return -1;
  }
  size = (size_t)width * (size_t)height;
  out->pixels = (uint8_t*)malloc(size);
  if (out->pixels == NULL || fread(out->pixels, 1, size, f) != size) {
    fprintf(stderr, "%s: truncated PGM\n", path);
    free(out->pixels);
    out->pixels = NULL;
    fclose(f);
    return -1;
  }
  fclose(f);
  out->width = (int)width;
  out->height = (int)height;
  return 0;
}
