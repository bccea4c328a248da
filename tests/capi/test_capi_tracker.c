/* The tracker through the C API on a real sequence: windows of
 * box_in_scene moving 4 px right and 2 px down per frame, handed over as
 * views into the scene (its row stride, no copy). The box must keep one
 * track id, be confirmed around its prediction on the frames without a
 * full detection, and stay where it is in the scene: its corners plus the
 * window's offset within 3 px of the first frame's.
 *   test_capi_tracker INDEX box_in_scene.pgm
 * C99, compiled with -std=c99 -Wall -Wextra -pedantic -Werror. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "keygraph/keygraph.h"
#include "pgm_read.h"

#define FRAMES 12
#define WIDTH 448
#define HEIGHT 336

int main(int argc, char** argv) {
  kg_index* index = NULL;
  kg_detector* detector = NULL;
  kg_tracker* tracker = NULL;
  kg_limits limits;
  kg_detection found[KG_MAX_DETECTIONS];
  kg_tracking_stats stats;
  pgm_image scene;
  double first[4][2];
  int k, c, track_id = -1, tracked = 0, failures = 0;
  if (argc != 3) {
    fprintf(stderr, "usage: test_capi_tracker INDEX box_in_scene.pgm\n");
    return 2;
  }
  if (pgm_read(argv[2], &scene) != 0) return 1;
  kg_limits_default(&limits);
  limits.max_width = WIDTH;
  limits.max_height = HEIGHT;
  if (scene.width < WIDTH + 4 * FRAMES || scene.height < HEIGHT + 2 * FRAMES ||
      kg_index_read(argv[1], &index) != KG_OK ||
      kg_detector_create(index, &limits, &detector) != KG_OK ||
      kg_tracker_create(detector, NULL, &tracker) != KG_OK) {
    fprintf(stderr, "test_capi_tracker: setup failed: %s\n", kg_last_error());
    return 1;
  }
  if (!kg_tracker_can_track(tracker)) {
    fprintf(stderr, "test_capi_tracker: the index has no appearances\n");
    ++failures;
  }
  for (k = 0; k < FRAMES && failures == 0; ++k) {
    const int dx = 4 * k, dy = 2 * k;
    kg_image image;
    size_t count = 0;
    double worst = 0.0;
    image.data = scene.pixels + (size_t)dy * (size_t)scene.width + (size_t)dx;
    image.width = WIDTH;
    image.height = HEIGHT;
    image.stride = scene.width;
    if (kg_tracker_process(tracker, &image, found, KG_MAX_DETECTIONS, &count) != KG_OK) {
      fprintf(stderr, "frame %d: %s\n", k, kg_last_error());
      ++failures;
      break;
    }
    if (count != 1 || strcmp(found[0].model_name, "box") != 0 || found[0].track_id < 0) {
      fprintf(stderr, "frame %d: %d objects, not the tracked box\n", k, (int)count);
      ++failures;
      continue;
    }
    if (k == 0) {
      track_id = found[0].track_id;
      for (c = 0; c < 4; ++c) {
        first[c][0] = found[0].corners[c][0];
        first[c][1] = found[0].corners[c][1];
      }
    }
    for (c = 0; c < 4; ++c) {
      const double ex = found[0].corners[c][0] + dx - first[c][0];
      const double ey = found[0].corners[c][1] + dy - first[c][1];
      const double e = sqrt(ex * ex + ey * ey);
      if (e > worst) worst = e;
    }
    tracked += found[0].tracked;
    printf("frame %2d offset (%2d, %2d): track %d %s, corners %.2f px from the first frame's\n", k,
           dx, dy, found[0].track_id, found[0].tracked ? "tracked " : "detected", worst);
    if (found[0].track_id != track_id || worst > 3.0) ++failures;
  }
  if (kg_tracker_stats(tracker, &stats) != KG_OK || stats.frames != FRAMES) ++failures;
  /* Detection on frame 0 and every 10th after it; the others tracked. */
  if (tracked < FRAMES - 2) {
    fprintf(stderr, "only %d of %d frames tracked\n", tracked, FRAMES);
    ++failures;
  }
  printf("%d frames, %d tracked, %lld detected: %s\n", FRAMES, tracked, stats.detected_frames,
         failures == 0 ? "ok" : "FAILED");
  kg_tracker_destroy(tracker);
  kg_detector_destroy(detector);
  kg_index_destroy(index);
  free(scene.pixels);
  return failures == 0 ? 0 : 1;
}
