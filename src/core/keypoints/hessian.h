// Determinant-of-Hessian keypoint detector over scales (the blob part of
// Hessian-Affine without the affine adaptation): scale-normalised
// det(H) = sigma^4 (Lxx Lyy - Lxy^2) on a Gaussian scale space, local maxima
// in a 3x3x3 neighbourhood of (x, y, scale) above a threshold, refined to
// sub-pixel position by a quadratic fit. The keypoint is the blob centre,
// which for these symmetric regions is the region centroid.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/image/plane.h"
#include "core/support/worker_pool.h"
#include "core/support/workspace.h"
#include "keygraph/image.h"
#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

class HessianDetector {
 public:
  explicit HessianDetector(std::pmr::memory_resource* memory = std::pmr::get_default_resource());

  // Sizes every buffer for images up to max_width x max_height, at most
  // max_keypoints output keypoints and max_candidates extremum candidates
  // per scale level; after this, detect() within those bounds allocates
  // nothing, and candidates beyond max_candidates are dropped (the weakest
  // rows last: scan order) instead of stored.
  // With threads > 1, buffers for that many row bands (at most kMaxBands)
  // are reserved too, for set_workers().
  void reserve(int max_width, int max_height, const KeypointParams& params, int max_keypoints,
               int max_candidates, int threads = 1);

  // Splits each scale level's work (blur, response, candidates, the scan
  // of the level below for maxima, halving) into row bands on `workers`
  // (null: the calling thread only): at most one band per thread and as
  // many as reserve() made room for, fewer on small levels. The keypoints
  // are the same, byte for byte, for any number of bands.
  void set_workers(WorkerPool* workers) { workers_ = workers; }
  static constexpr int kMaxBands = 8;

  // Clears `out` and fills it with at most `max_keypoints` keypoints, the
  // strongest first (ties broken by position so the result is
  // deterministic). Uses params.hessian_threshold, hessian_octaves,
  // hessian_levels and the fine levels below the first octave
  // (hessian_fine_levels, hessian_fine_threshold). Buffers are kept
  // between calls and reused. Returns false when candidates were dropped
  // (reserve()).
  bool detect(ImageView image, const KeypointParams& params, int max_keypoints,
              WorkVector<Keypoint>& out);
  // The same into a std::vector (desktop and tests).
  void detect(ImageView image, const KeypointParams& params, int max_keypoints,
              std::vector<Keypoint>& out);

 private:
  // What one row band works with: its blur row, candidate flags, the two
  // response rows above and below it that the 3x3x3 test reads, its
  // candidates of the two levels last computed (slot: the level's place in
  // the octave % 2), which it scans itself, and (bands after the first) the
  // heap of its strongest maxima, joined at the end.
  struct Band {
    explicit Band(std::pmr::memory_resource* memory)
        : scratch(memory),
          mask(memory),
          halo(memory),
          candidates{WorkVector<std::int32_t>(memory), WorkVector<std::int32_t>(memory)},
          strongest(memory) {}
    Plane<float> scratch;
    WorkVector<std::uint8_t> mask;
    Plane<float> halo;
    std::array<WorkVector<std::int32_t>, 2> candidates;
    std::array<bool, 2> complete{true, true};  // no candidate of the slot's list dropped
    WorkVector<Keypoint> strongest;
  };
  struct Level;
  // Runs one level's work on `bands` row bands (below).
  void run_level(const Level& level, int bands);
  // How many ints of band `band`'s candidates in `slot` one list would
  // have kept: the bands' lists, joined in scan order, cut at
  // max_candidate_ints_.
  std::size_t kept_candidates(int slot, int band) const;
  // No candidate of the level in `slot` dropped.
  bool candidates_complete(int slot, int bands) const;
  // Bands for a w x h level: one per thread, fewer on small levels.
  int bands_for(int w, int h) const;

  // Only the planes in use at once are kept: two Gaussian levels (blurring
  // ping-pongs between them), the next octave's first level, and the three
  // response levels the 3x3x3 test reads (a ring).
  std::array<Plane<float>, 2> levels_;
  std::array<Plane<float>, 3> responses_;
  Plane<float> next_octave_;  // halved level: first level of the next octave
  std::array<Band, kMaxBands> bands_;
  int reserved_bands_ = 1;
  WorkerPool* workers_ = nullptr;
  std::size_t max_candidate_ints_ = static_cast<std::size_t>(-1);  // 2 per candidate
  WorkVector<Keypoint> copy_;  // the std::vector overload's result, before the copy
};

}  // namespace kg
