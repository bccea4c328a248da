/* The C API on real frames: finds an index's models in PGM frames and
 * prints one line per detection,
 *   FRAME MODEL X0 Y0 X1 Y1 X2 Y2 X3 Y3 inliers=N confidence=C
 * (corners in the model outline's order, frame pixels, 4 decimals), or
 * "FRAME none"; the bindings' programs and the C++ reference (find_cpp.cpp)
 * print the same, and compare_find.py holds them to the same corners. Each
 * frame is handed over in a buffer whose rows are 40 bytes longer than the
 * image, as a camera's Y plane often is.
 *   kg_find_c INDEX FRAME.pgm...
 * C99, compiled with -std=c99 -Wall -Wextra -pedantic -Werror. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "keygraph/keygraph.h"
#include "pgm_read.h"

#define ROW_PADDING 40

static const char* base_name(const char* path) {
  const char* slash = strrchr(path, '/');
  return slash == NULL ? path : slash + 1;
}

/* The frame copied into rows of width + ROW_PADDING bytes (padding 0xA5). */
static uint8_t* padded_copy(const pgm_image* frame, ptrdiff_t* stride) {
  const size_t row = (size_t)frame->width + ROW_PADDING;
  uint8_t* data = (uint8_t*)malloc(row * (size_t)frame->height);
  int y;
  if (data == NULL) return NULL;
  memset(data, 0xA5, row * (size_t)frame->height);
  for (y = 0; y < frame->height; ++y)
    memcpy(data + (size_t)y * row, frame->pixels + (size_t)y * (size_t)frame->width,
           (size_t)frame->width);
  *stride = (ptrdiff_t)row;
  return data;
}

int main(int argc, char** argv) {
  kg_index* index = NULL;
  kg_detector* detector = NULL;
  kg_limits limits;
  kg_detection found[KG_MAX_DETECTIONS];
  pgm_image* frames;
  int frame_count, i, exit_code = 0;
  if (argc < 3) {
    fprintf(stderr, "usage: kg_find_c INDEX FRAME.pgm...\n");
    return 2;
  }
  if (kg_index_open(argv[1], &index) != KG_OK) {
    fprintf(stderr, "kg_find_c: %s\n", kg_last_error());
    return 1;
  }
  frame_count = argc - 2;
  frames = (pgm_image*)calloc((size_t)frame_count, sizeof *frames);
  kg_limits_default(&limits);
  limits.max_width = limits.max_height = 1;
  for (i = 0; frames != NULL && i < frame_count; ++i) {
    if (pgm_read(argv[i + 2], &frames[i]) != 0) {
      exit_code = 1;
      break;
    }
    if (frames[i].width > limits.max_width) limits.max_width = frames[i].width;
    if (frames[i].height > limits.max_height) limits.max_height = frames[i].height;
  }
  if (frames == NULL || exit_code != 0) {
    exit_code = 1;
  } else if (kg_detector_create(index, &limits, &detector) != KG_OK) {
    fprintf(stderr, "kg_find_c: %s\n", kg_last_error());
    exit_code = 1;
  }
  for (i = 0; exit_code == 0 && i < frame_count; ++i) {
    kg_image image;
    size_t count = 0, d;
    int c;
    uint8_t* data = padded_copy(&frames[i], &image.stride);
    if (data == NULL) {
      exit_code = 1;
      break;
    }
    image.data = data;
    image.width = frames[i].width;
    image.height = frames[i].height;
    if (kg_detect(detector, &image, found, KG_MAX_DETECTIONS, &count) != KG_OK) {
      fprintf(stderr, "kg_find_c: %s: %s\n", base_name(argv[i + 2]), kg_last_error());
      exit_code = 1;
    }
    if (exit_code == 0 && count == 0) printf("%s none\n", base_name(argv[i + 2]));
    for (d = 0; exit_code == 0 && d < count; ++d) {
      printf("%s %s", base_name(argv[i + 2]), found[d].model_name);
      for (c = 0; c < 4; ++c) printf(" %.4f %.4f", found[d].corners[c][0], found[d].corners[c][1]);
      printf(" inliers=%d confidence=%.4f\n", found[d].inliers, found[d].confidence);
    }
    free(data);
  }
  for (i = 0; frames != NULL && i < frame_count; ++i) free(frames[i].pixels);
  free(frames);
  kg_detector_destroy(detector);
  kg_index_destroy(index);
  return exit_code;
}
