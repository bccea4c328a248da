#include "core/pose/pose_stage.h"

#include <algorithm>

#include "core/keygraphs/keygraph.h"
#include "core/support/rng.h"

namespace kg {

namespace {

// Each model's own random stream: its poses do not depend on which other
// models had correspondences, nor on the thread that estimates them.
Rng model_rng(const Params& params, int model) {
  return Rng(params.ransac.seed ^ (0x9e3779b97f4a7c15ULL * static_cast<std::uint64_t>(model + 1)));
}

bool passed(const PoseStage::Clock::time_point* deadline) {
  return deadline != nullptr && PoseStage::Clock::now() > *deadline;
}

}  // namespace

PoseStage::PoseStage(std::pmr::memory_resource* memory)
    : memory_(memory),
      grouped_(memory),
      model_begin_(memory),
      tasks_(memory),
      estimators_(memory),
      found_(memory) {}

void PoseStage::reserve(int threads, int max_matches, int k, std::uint32_t max_model_keypoints,
                        int max_appearance_pixels, int models, bool fill) {
  const auto n = static_cast<std::size_t>(std::max(0, max_matches));
  const auto m = static_cast<std::size_t>(std::max(0, models));
  const auto t = static_cast<std::size_t>(std::max(1, threads));
  grouped_.reserve(n);
  model_begin_.reserve(m + 1);
  estimators_.reserve(t);
  estimators_.clear();
  // One thread estimates the models in order straight into the output.
  const bool parallel = t > 1;
  if (parallel) {
    tasks_.reserve(m);
    found_.reserve(t);
  }
  found_.clear();
  for (std::size_t i = 0; i < t; ++i) {
    // The measuring pass must not write into its placeholder memory: a
    // stand-in on the stack reserves what each estimator would.
    PoseEstimator stand_in(memory_);
    PoseEstimator& e = fill ? estimators_.emplace_back(memory_) : stand_in;
    e.reserve(max_matches, k, max_model_keypoints, max_appearance_pixels);
    if (fill && parallel) found_.emplace_back();
  }
}

void PoseStage::group(const ModelIndex& index, const KeygraphMatch* matches, std::size_t n) {
  // A counting sort by model that keeps the selection's order within each.
  const auto models = static_cast<std::size_t>(index.model_count());
  model_begin_.assign(models + 1, 0);
  for (std::size_t i = 0; i < n; ++i)
    ++model_begin_[static_cast<std::size_t>(matches[i].model_id) + 1];
  for (std::size_t i = 0; i < models; ++i) model_begin_[i + 1] += model_begin_[i];
  grouped_.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    grouped_[model_begin_[static_cast<std::size_t>(matches[i].model_id)]++] = matches[i];
  // model_begin_[m] is now model m's end: shift it back to its begin.
  for (std::size_t i = models; i > 0; --i) model_begin_[i] = model_begin_[i - 1];
  model_begin_[0] = 0;
}

PoseStage::Result PoseStage::estimate_in_order(const ModelIndex& index, const Params& params,
                                               const Point2f* scene_points,
                                               const FrameKeypoints& frame, int max_out,
                                               WorkerPool* workers,
                                               const Clock::time_point* deadline,
                                               DetectionList& out) {
  Result r;
  PoseEstimator& pose = estimators_[0];
  // The pool is free while the models run in order; not afterwards, when
  // this estimator may run a model as a task of the pool.
  pose.set_workers(workers);
  const PoseEstimator::AlignCounts before = pose.align_counts();
  for (int model = 0; model < index.model_count(); ++model) {
    const std::uint32_t begin = model_begin_[static_cast<std::size_t>(model)];
    const std::uint32_t end = model_begin_[static_cast<std::size_t>(model) + 1];
    if (begin == end) continue;
    if (passed(deadline)) {
      r.out_of_time = true;
      break;
    }
    Rng rng = model_rng(params, model);
    r.ransac_iterations +=
        pose.estimate(index, params, model, grouped_.data() + begin, static_cast<int>(end - begin),
                      scene_points, frame, rng, max_out, out, r.truncated);
  }
  pose.set_workers(nullptr);
  r.alignments = pose.align_counts().aligned - before.aligned;
  r.alignments_abandoned = pose.align_counts().abandoned - before.abandoned;
  return r;
}

PoseStage::Result PoseStage::estimate(const ModelIndex& index, const Params& params,
                                      const KeygraphMatch* matches, std::size_t n,
                                      const Point2f* scene_points, const FrameKeypoints& frame,
                                      int max_out, WorkerPool* workers,
                                      const Clock::time_point* deadline, DetectionList& out) {
  group(index, matches, n);
  for (PoseEstimator& e : estimators_) {
    e.set_barren_draws(barren_draws_);
    e.set_align_min_ncc(align_min_ncc_, align_coarse_min_ncc_);
  }
  const int threads =
      workers == nullptr ? 1 : std::min(workers->threads(), static_cast<int>(found_.size()));
  if (threads <= 1)
    return estimate_in_order(index, params, scene_points, frame, max_out, nullptr, deadline, out);
  const int least = sample_size(params.graph.structure);  // fewer estimate nothing
  tasks_.clear();
  for (int model = 0; model < index.model_count(); ++model) {
    Task t;
    t.model = model;
    t.begin = model_begin_[static_cast<std::size_t>(model)];
    t.end = model_begin_[static_cast<std::size_t>(model) + 1];
    if (t.end - t.begin >= static_cast<std::uint32_t>(least)) tasks_.push_back(t);
  }
  if (tasks_.size() <= 1)
    return estimate_in_order(index, params, scene_points, frame, max_out, workers, deadline, out);

  // The largest models first, so that no thread starts a long one last
  // (ties by id: the order does not depend on timing).
  std::sort(tasks_.begin(), tasks_.end(), [](const Task& a, const Task& b) {
    const std::uint32_t na = a.end - a.begin, nb = b.end - b.begin;
    return na != nb ? na > nb : a.model < b.model;
  });
  for (DetectionList& list : found_) list.clear();
  const std::size_t base = out.size();
  auto run_task = [&](int i, int worker) {
    Task& t = tasks_[static_cast<std::size_t>(i)];
    t.worker = worker;
    if (passed(deadline)) {
      t.skipped = true;
      return;
    }
    t.skipped = false;
    DetectionList& list = found_[static_cast<std::size_t>(worker)];
    t.first = static_cast<std::uint32_t>(list.size());
    t.truncated = false;
    Rng rng = model_rng(params, t.model);
    PoseEstimator& pose = estimators_[static_cast<std::size_t>(worker)];
    const PoseEstimator::AlignCounts before = pose.align_counts();
    t.iterations = pose.estimate(index, params, t.model, grouped_.data() + t.begin,
                                 static_cast<int>(t.end - t.begin), scene_points, frame, rng,
                                 static_cast<int>(DetectionList::capacity()), list, t.truncated);
    t.alignments = pose.align_counts().aligned - before.aligned;
    t.abandoned = pose.align_counts().abandoned - before.abandoned;
    t.last = static_cast<std::uint32_t>(list.size());
  };
  // A thread out of models helps the ones still running with their
  // appearance alignments (WorkerPool::run_with_help): a frame's one found
  // object is the longest task.
  for (PoseEstimator& e : estimators_) e.set_workers(workers);
  workers->run_with_help(static_cast<int>(tasks_.size()), run_task);
  for (PoseEstimator& e : estimators_) e.set_workers(nullptr);

  // Back in model order.
  std::sort(tasks_.begin(), tasks_.end(),
            [](const Task& a, const Task& b) { return a.model < b.model; });
  // What one thread would output: the models up to the first one skipped.
  std::size_t total = 0;
  bool overflow = false;
  for (const Task& t : tasks_) {
    if (t.skipped) break;
    total += t.last - t.first;
    overflow = overflow || t.truncated;
  }
  const std::size_t most = static_cast<std::size_t>(std::max(0, max_out));
  if ((overflow || base + total > most) && !passed(deadline)) {
    // One thread would have reached max_out (and cut a model's attempts
    // short): its answer, from the start. (With the budget spent a rerun
    // would find nothing: the instances found are cut at max_out instead.)
    return estimate_in_order(index, params, scene_points, frame, max_out, workers, deadline, out);
  }
  Result r;
  for (const Task& t : tasks_) {
    if (t.skipped) {
      r.out_of_time = true;
      break;
    }
    const DetectionList& list = found_[static_cast<std::size_t>(t.worker)];
    for (std::uint32_t i = t.first; i < t.last && !r.truncated; ++i) {
      if (out.size() >= most) {
        r.truncated = true;
      } else {
        out.push_back(list[i]);
      }
    }
    r.truncated = r.truncated || t.truncated;
    r.ransac_iterations += t.iterations;
    r.alignments += t.alignments;
    r.alignments_abandoned += t.abandoned;
  }
  return r;
}

}  // namespace kg
