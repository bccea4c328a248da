/* Bad input through the C API: NULL handles and pointers, bad image
 * layouts, frames larger than the limits, bad limits, options and model
 * ids, caller workspaces too small or misaligned, missing files and
 * corrupt index buffers (truncated, bit-flipped). Every case must return
 * its status with a message, never crash, and the detector must still work
 * afterwards. Also run under the sanitizers (the sanitize preset).
 *   test_capi_errors INDEX.kgi OLD_INDEX.kgi
 * OLD_INDEX is of format 6.1, without model appearances (tracking then
 * detects every frame).
 * C99, compiled with -std=c99 -Wall -Wextra -pedantic -Werror. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "keygraph/keygraph.h"

static int g_passed = 0, g_failed = 0;

static void check(int ok, const char* what, int line) {
  if (ok) {
    ++g_passed;
  } else {
    ++g_failed;
    fprintf(stderr, "test_capi_errors.c:%d: FAILED: %s\n", line, what);
  }
}
#define CHECK(condition) check((condition) ? 1 : 0, #condition, __LINE__)

/* `status` is `expected` and this thread's message contains `part`. */
static void check_fails(kg_status status, kg_status expected, const char* part, int line) {
  const char* message = kg_last_error();
  char what[600];
  snprintf(what, sizeof what, "status %s (expected %s), message '%s' (expected to contain '%s')",
           kg_status_name(status), kg_status_name(expected), message, part);
  check(status == expected && message != NULL && strstr(message, part) != NULL, what, line);
}
#define CHECK_FAILS(call, expected, part) check_fails((call), (expected), (part), __LINE__)

/* A buffer whose data starts at a 64-byte boundary, with `size` bytes. */
typedef struct aligned_buffer {
  void* block;
  uint8_t* data;
  size_t size;
} aligned_buffer;

static int aligned_alloc_copy(aligned_buffer* out, const uint8_t* bytes, size_t size) {
  out->block = malloc(size + 128);
  if (out->block == NULL) return -1;
  out->data = (uint8_t*)out->block + (64 - (uintptr_t)out->block % 64);
  out->size = size;
  if (bytes != NULL) memcpy(out->data, bytes, size);
  return 0;
}

static uint8_t* read_file(const char* path, size_t* size) {
  FILE* f = fopen(path, "rb");
  long length = -1;
  uint8_t* data = NULL;
  if (f == NULL) return NULL;
  if (fseek(f, 0, SEEK_END) == 0) length = ftell(f);
  if (length > 0 && fseek(f, 0, SEEK_SET) == 0) data = (uint8_t*)malloc((size_t)length);
  if (data != NULL && fread(data, 1, (size_t)length, f) != (size_t)length) {
    free(data);
    data = NULL;
  }
  fclose(f);
  *size = data == NULL ? 0 : (size_t)length;
  return data;
}

static void test_status_names(void) {
  CHECK(strcmp(kg_status_name(KG_OK), "Ok") == 0);
  CHECK(strcmp(kg_status_name(KG_INVALID_ARGUMENT), "InvalidArgument") == 0);
  CHECK(strcmp(kg_status_name(KG_CORRUPT_DATA), "CorruptData") == 0);
  CHECK(strcmp(kg_status_name(KG_BAD_FRAME), "BadFrame") == 0);
  CHECK(strcmp(kg_status_name((kg_status)99), "Unknown") == 0);
  CHECK(strcmp(kg_status_name((kg_status)-1), "Unknown") == 0);
  CHECK(kg_version() != NULL && strchr(kg_version(), '.') != NULL);
}

static void test_opening(const char* path) {
  kg_index* index = (kg_index*)&g_passed; /* not NULL: failures must reset it */
  int major = 0, minor = 0;
  CHECK_FAILS(kg_index_open(NULL, &index), KG_INVALID_ARGUMENT, "path is NULL");
  CHECK(index == NULL);
  CHECK_FAILS(kg_index_open(path, NULL), KG_INVALID_ARGUMENT, "out is NULL");
  CHECK_FAILS(kg_index_read(NULL, &index), KG_INVALID_ARGUMENT, "path is NULL");
  CHECK_FAILS(kg_index_open("/nonexistent/keygraph/signs.kgi", &index), KG_NOT_FOUND, "signs.kgi");
  CHECK(index == NULL);
  CHECK_FAILS(kg_index_read("/", &index), KG_INVALID_ARGUMENT, "is a directory");
  CHECK_FAILS(kg_index_from_memory(NULL, 100, &index), KG_INVALID_ARGUMENT, "data is NULL");
  CHECK_FAILS(kg_index_version(NULL, &major, &minor), KG_INVALID_ARGUMENT, "NULL");
  CHECK(kg_index_model_count(NULL) == 0);
  CHECK(kg_index_model_name(NULL, 0) == NULL);
  kg_index_destroy(NULL);
  CHECK(kg_index_read(path, &index) == KG_OK);
  CHECK(kg_index_version(index, &major, &minor) == KG_OK && major >= 6);
  CHECK(kg_index_model_count(index) >= 1);
  CHECK(kg_index_model_name(index, -1) == NULL);
  CHECK(kg_index_model_name(index, kg_index_model_count(index)) == NULL);
  CHECK_FAILS(kg_index_model_info(index, 1000, NULL), KG_INVALID_ARGUMENT, "NULL");
  {
    kg_model_info info;
    CHECK_FAILS(kg_index_model_info(index, 1000, &info), KG_INVALID_ARGUMENT, "no such model");
    CHECK(kg_index_model_info(index, 0, &info) == KG_OK);
    CHECK(info.width > 0 && info.height > 0 && info.keypoints > 0);
    CHECK(strcmp(info.name, kg_index_model_name(index, 0)) == 0);
  }
  kg_index_destroy(index);
}

/* Misaligned, truncated and bit-flipped copies of the index's bytes: each
 * is refused with a message or, for flips the checksums cannot see (none
 * expected), opens; none crashes. */
static void test_corrupt_buffers(const uint8_t* bytes, size_t size) {
  aligned_buffer buffer;
  kg_index* index = NULL;
  size_t cut, bit;
  int refused = 0, tried = 0;
  if (aligned_alloc_copy(&buffer, bytes, size) != 0) {
    CHECK(!"out of memory");
    return;
  }
  CHECK(kg_index_from_memory(buffer.data, size, &index) == KG_OK);
  kg_index_destroy(index);
  memmove(buffer.data + 1, buffer.data, size);
  CHECK_FAILS(kg_index_from_memory(buffer.data + 1, size, &index), KG_INVALID_ARGUMENT,
              "64-byte aligned");
  CHECK(index == NULL);
  memmove(buffer.data, buffer.data + 1, size);
  CHECK_FAILS(kg_index_from_memory(buffer.data, 0, &index), KG_CORRUPT_DATA, "");
  for (cut = 1; cut < size; cut = cut < 256 ? cut + 7 : cut * 3 / 2) {
    const kg_status s = kg_index_from_memory(buffer.data, cut, &index);
    ++tried;
    refused += s != KG_OK && index == NULL && kg_last_error()[0] != '\0';
  }
  CHECK(refused == tried);
  refused = tried = 0;
  for (bit = 3; bit < size * 8; bit += size * 8 / 97 + 1) {
    kg_status s;
    buffer.data[bit / 8] ^= (uint8_t)(1u << (bit % 8));
    s = kg_index_from_memory(buffer.data, size, &index);
    ++tried;
    refused += s != KG_OK && index == NULL;
    kg_index_destroy(index);
    index = NULL;
    buffer.data[bit / 8] ^= (uint8_t)(1u << (bit % 8));
  }
  CHECK(refused == tried);
  printf("corrupt buffers: %d bit flips refused\n", refused);
  free(buffer.block);
}

static void test_detector(const char* path) {
  kg_index* index = NULL;
  kg_detector* detector = (kg_detector*)&g_passed;
  kg_limits limits;
  kg_detection found[KG_MAX_DETECTIONS];
  kg_stats stats;
  kg_image image;
  size_t count = 99;
  uint8_t* pixels = (uint8_t*)calloc(200 * 100, 1);
  int32_t model = 0;
  if (pixels == NULL || kg_index_read(path, &index) != KG_OK) {
    CHECK(!"setup");
    free(pixels);
    return;
  }
  kg_limits_default(&limits);
  CHECK(limits.max_width == 640 && limits.max_height == 480 && limits.threads == 1);
  limits.max_width = 200;
  limits.max_height = 100;
  CHECK_FAILS(kg_detector_create(NULL, &limits, &detector), KG_INVALID_ARGUMENT, "index is NULL");
  CHECK(detector == NULL);
  CHECK_FAILS(kg_detector_create(index, &limits, NULL), KG_INVALID_ARGUMENT, "out is NULL");
  limits.max_width = 0;
  CHECK_FAILS(kg_detector_create(index, &limits, &detector), KG_INVALID_ARGUMENT, "limits");
  limits.max_width = 200;
  limits.threads = 65;
  CHECK_FAILS(kg_detector_create(index, &limits, &detector), KG_INVALID_ARGUMENT, "threads");
  limits.threads = 1;
  limits.max_detections = KG_MAX_DETECTIONS + 1;
  CHECK_FAILS(kg_detector_create(index, &limits, &detector), KG_INVALID_ARGUMENT, "max_detections");
  CHECK(kg_detector_workspace_bytes(index, &limits) == 0);
  CHECK(kg_detector_workspace_bytes(NULL, NULL) == 0);
  limits.max_detections = 16;
  CHECK(kg_detector_create(index, &limits, &detector) == KG_OK && detector != NULL);

  image.data = pixels;
  image.width = 200;
  image.height = 100;
  image.stride = 200;
  CHECK_FAILS(kg_detect(NULL, &image, found, KG_MAX_DETECTIONS, &count), KG_INVALID_ARGUMENT,
              "NULL");
  CHECK(count == 0);
  CHECK_FAILS(kg_detect(detector, NULL, found, KG_MAX_DETECTIONS, &count), KG_INVALID_ARGUMENT,
              "NULL");
  CHECK_FAILS(kg_detect(detector, &image, NULL, KG_MAX_DETECTIONS, &count), KG_INVALID_ARGUMENT,
              "NULL");
  CHECK_FAILS(kg_detect(detector, &image, found, KG_MAX_DETECTIONS, NULL), KG_INVALID_ARGUMENT,
              "NULL");
  image.stride = 199;
  CHECK_FAILS(kg_detect(detector, &image, found, KG_MAX_DETECTIONS, &count), KG_INVALID_ARGUMENT,
              "stride >= width");
  image.stride = -200;
  CHECK_FAILS(kg_detect(detector, &image, found, KG_MAX_DETECTIONS, &count), KG_INVALID_ARGUMENT,
              "stride >= width");
  image.stride = 200;
  image.width = 0;
  CHECK_FAILS(kg_detect(detector, &image, found, KG_MAX_DETECTIONS, &count), KG_INVALID_ARGUMENT,
              "width and height");
  image.width = 200;
  image.height = -5;
  CHECK_FAILS(kg_detect(detector, &image, found, KG_MAX_DETECTIONS, &count), KG_INVALID_ARGUMENT,
              "width and height");
  image.height = 100;
  image.data = NULL;
  CHECK_FAILS(kg_detect(detector, &image, found, KG_MAX_DETECTIONS, &count), KG_INVALID_ARGUMENT,
              "data is NULL");
  image.data = pixels;
  /* 100 x 200 fits neither limit's side the other way round. */
  image.width = 100;
  image.height = 200;
  image.stride = 100;
  CHECK_FAILS(kg_detect(detector, &image, found, KG_MAX_DETECTIONS, &count), KG_INVALID_ARGUMENT,
              "larger than the detector's limits");
  image.width = 200;
  image.height = 100;
  image.stride = 200;
  /* A flat frame: nothing found, and no room needed. */
  CHECK(kg_detect(detector, &image, NULL, 0, &count) == KG_OK && count == 0);
  CHECK(kg_detect(detector, &image, found, KG_MAX_DETECTIONS, &count) == KG_OK && count == 0);

  CHECK_FAILS(kg_detector_set_option(NULL, "ransac.seed", "7"), KG_INVALID_ARGUMENT, "NULL");
  CHECK_FAILS(kg_detector_set_option(detector, NULL, "7"), KG_INVALID_ARGUMENT, "NULL");
  CHECK_FAILS(kg_detector_set_option(detector, "ransac.seed", NULL), KG_INVALID_ARGUMENT, "NULL");
  CHECK_FAILS(kg_detector_set_option(detector, "no.such", "1"), KG_INVALID_ARGUMENT, "no.such");
  CHECK_FAILS(kg_detector_set_option(detector, "graph.structure", "4"), KG_INVALID_ARGUMENT,
              "fixed by the index");
  CHECK_FAILS(kg_detector_set_option(detector, "ransac.max_iterations", "many"),
              KG_INVALID_ARGUMENT, "many");
  CHECK_FAILS(kg_detector_set_option(detector, "min_confidence", "2"), KG_INVALID_ARGUMENT,
              "min_confidence");
  CHECK(kg_detector_set_option(detector, "ransac.seed", "7") == KG_OK);
  CHECK(kg_detector_set_option(detector, "min_confidence", "0.5") == KG_OK);
  CHECK_FAILS(kg_detector_set_models(NULL, &model, 1), KG_INVALID_ARGUMENT, "NULL");
  CHECK_FAILS(kg_detector_set_models(detector, NULL, 1), KG_INVALID_ARGUMENT, "ids is NULL");
  model = kg_index_model_count(index);
  CHECK_FAILS(kg_detector_set_models(detector, &model, 1), KG_INVALID_ARGUMENT, "not in the index");
  model = 0;
  CHECK(kg_detector_set_models(detector, &model, 1) == KG_OK);
  CHECK(kg_detector_set_models(detector, NULL, 0) == KG_OK);

  CHECK_FAILS(kg_detector_stats(NULL, &stats), KG_INVALID_ARGUMENT, "NULL");
  CHECK_FAILS(kg_detector_stats(detector, NULL), KG_INVALID_ARGUMENT, "NULL");
  CHECK(kg_detect(detector, &image, found, KG_MAX_DETECTIONS, &count) == KG_OK);
  CHECK(kg_detector_stats(detector, &stats) == KG_OK && stats.stopped_early == NULL);
  kg_detector_destroy(detector);
  kg_detector_destroy(NULL);

  /* A caller's workspace: too small, misaligned, then right. */
  {
    const size_t bytes = kg_detector_workspace_bytes(index, &limits);
    aligned_buffer workspace;
    CHECK(bytes > 0);
    if (bytes > 0 && aligned_alloc_copy(&workspace, NULL, bytes + 64) == 0) {
      CHECK_FAILS(kg_detector_create_in(index, &limits, NULL, bytes, &detector),
                  KG_INVALID_ARGUMENT, "buffer is NULL");
      CHECK_FAILS(kg_detector_create_in(index, &limits, workspace.data, bytes / 2, &detector),
                  KG_RESOURCE_EXHAUSTED, "too small");
      CHECK(detector == NULL);
      CHECK_FAILS(kg_detector_create_in(index, &limits, workspace.data + 8, bytes, &detector),
                  KG_INVALID_ARGUMENT, "aligned");
      CHECK(kg_detector_create_in(index, &limits, workspace.data, bytes, &detector) == KG_OK);
      CHECK(kg_detect(detector, &image, found, KG_MAX_DETECTIONS, &count) == KG_OK);
      kg_detector_destroy(detector);
      free(workspace.block);
    }
  }
  kg_index_destroy(index);
  free(pixels);
}

static void test_tracker(const char* path, const char* old_path) {
  kg_index* index = NULL;
  kg_detector* detector = NULL;
  kg_tracker* tracker = (kg_tracker*)&g_passed;
  kg_tracker_options options;
  kg_tracking_stats stats;
  kg_limits limits;
  kg_detection found[KG_MAX_DETECTIONS];
  kg_image image;
  size_t count = 0;
  uint8_t* pixels = (uint8_t*)calloc(320 * 240, 1);
  kg_limits_default(&limits);
  limits.max_width = 320;
  limits.max_height = 240;
  if (pixels == NULL || kg_index_read(path, &index) != KG_OK ||
      kg_detector_create(index, &limits, &detector) != KG_OK) {
    CHECK(!"setup");
    free(pixels);
    kg_index_destroy(index);
    return;
  }
  kg_tracker_options_default(&options);
  CHECK(options.detect_interval == 10 && options.max_tracks == 16 && options.smoothing == 0.0);
  CHECK_FAILS(kg_tracker_create(NULL, &options, &tracker), KG_INVALID_ARGUMENT, "detector is NULL");
  CHECK(tracker == NULL);
  CHECK_FAILS(kg_tracker_create(detector, &options, NULL), KG_INVALID_ARGUMENT, "out is NULL");
  options.detect_interval = 0;
  CHECK_FAILS(kg_tracker_create(detector, &options, &tracker), KG_INVALID_ARGUMENT,
              "detect_interval");
  options.detect_interval = 10;
  options.smoothing = 1.0;
  CHECK_FAILS(kg_tracker_create(detector, &options, &tracker), KG_INVALID_ARGUMENT, "smoothing");
  CHECK(tracker == NULL);
  CHECK(kg_tracker_create(detector, NULL, &tracker) == KG_OK && kg_tracker_can_track(tracker) == 1);
  image.data = pixels;
  image.width = 321;
  image.height = 240;
  image.stride = 321;
  CHECK_FAILS(kg_tracker_process(tracker, &image, found, KG_MAX_DETECTIONS, &count),
              KG_INVALID_ARGUMENT, "larger than the detector's limits");
  image.width = 320;
  image.stride = 100;
  CHECK_FAILS(kg_tracker_process(tracker, &image, found, KG_MAX_DETECTIONS, &count),
              KG_INVALID_ARGUMENT, "stride >= width");
  image.stride = 320;
  CHECK_FAILS(kg_tracker_process(NULL, &image, found, KG_MAX_DETECTIONS, &count),
              KG_INVALID_ARGUMENT, "NULL");
  CHECK_FAILS(kg_tracker_process(tracker, &image, found, KG_MAX_DETECTIONS, NULL),
              KG_INVALID_ARGUMENT, "NULL");
  CHECK(kg_tracker_process(tracker, &image, found, KG_MAX_DETECTIONS, &count) == KG_OK &&
        count == 0);
  CHECK(kg_tracker_stats(tracker, &stats) == KG_OK && stats.frames == 1 && stats.detected == 1);
  CHECK_FAILS(kg_tracker_stats(NULL, &stats), KG_INVALID_ARGUMENT, "NULL");
  kg_tracker_reset(tracker);
  kg_tracker_reset(NULL);
  CHECK(kg_tracker_stats(tracker, &stats) == KG_OK && stats.frames == 0);
  kg_tracker_destroy(tracker);
  kg_tracker_destroy(NULL);
  CHECK(kg_tracker_can_track(NULL) == 0);
  kg_detector_destroy(detector);
  kg_index_destroy(index);
  /* An index without appearances (format 6.1): made, detects every frame. */
  index = NULL;
  detector = NULL;
  tracker = NULL;
  if (kg_index_read(old_path, &index) == KG_OK &&
      kg_detector_create(index, &limits, &detector) == KG_OK) {
    CHECK(kg_tracker_create(detector, NULL, &tracker) == KG_OK &&
          kg_tracker_can_track(tracker) == 0);
    CHECK(kg_tracker_process(tracker, &image, found, KG_MAX_DETECTIONS, &count) == KG_OK);
    options.smoothing = 2.0; /* still an error there */
    kg_tracker_destroy(tracker);
    tracker = NULL;
    CHECK_FAILS(kg_tracker_create(detector, &options, &tracker), KG_INVALID_ARGUMENT, "smoothing");
  } else {
    CHECK(!"the format 6.1 index opens");
  }
  kg_detector_destroy(detector);
  kg_index_destroy(index);
  free(pixels);
}

int main(int argc, char** argv) {
  uint8_t* bytes;
  size_t size = 0;
  if (argc != 3) {
    fprintf(stderr, "usage: test_capi_errors INDEX.kgi OLD_INDEX.kgi\n");
    return 2;
  }
  bytes = read_file(argv[1], &size);
  if (bytes == NULL) {
    fprintf(stderr, "test_capi_errors: cannot read %s\n", argv[1]);
    return 1;
  }
  test_status_names();
  test_opening(argv[1]);
  test_corrupt_buffers(bytes, size);
  test_detector(argv[1]);
  test_tracker(argv[1], argv[2]);
  free(bytes);
  printf("%d passed, %d failed\n", g_passed, g_failed);
  return g_failed == 0 ? 0 : 1;
}
