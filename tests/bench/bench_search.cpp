// Query throughput of arc-descriptor search: the flat kd-tree of the model
// index (core/index/kdtree.h, float descriptors), FLANN's exact single kd-tree and
// brute force, for radius queries (r = 0.3, the similarity threshold) and
// 8-nearest queries, over 10 k, 100 k and 1 M clustered unit descriptors.
// One thread; every method answers the same queries exactly.
//
//   cmake --preset bench && cmake --build --preset bench
//   build/bench/tests/bench/bench_search
//
// Figures: docs/RESULTS.md, "Search tree throughput".
#include <benchmark/benchmark.h>

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <flann/flann.hpp>

#include "bench/search_data.h"
#include "core/description/arc_types.h"
#include "core/index/kdtree.h"
#include "core/support/rng.h"

namespace kg {
namespace {

constexpr float kRadius = 0.3f;
constexpr int kK = 8;
constexpr std::uint32_t kQueries = 1024;  // cycled through by every benchmark
constexpr std::int64_t kSizes[] = {10'000, 100'000, 1'000'000};

// Data points and queries from the same clusters (queries are not data points).
struct Dataset {
  std::vector<ArcDescriptor> data;
  std::vector<ArcDescriptor> queries;
  test::FlatTree tree;
  std::unique_ptr<flann::KDTreeSingleIndex<flann::L2<float>>> flann_tree;
};

const Dataset& dataset(std::int64_t n) {
  static std::map<std::int64_t, std::unique_ptr<Dataset>> cache;
  auto& slot = cache[n];
  if (!slot) {
    slot = std::make_unique<Dataset>();
    Dataset& d = *slot;
    Rng rng(static_cast<std::uint64_t>(n));
    d.data = test::clustered_descriptors(rng, static_cast<std::uint32_t>(n) + kQueries);
    d.queries.assign(d.data.end() - kQueries, d.data.end());
    d.data.resize(static_cast<std::size_t>(n));
    test::build_flat_tree(d.data, d.tree);
    const flann::Matrix<float> m(d.data[0].data(), d.data.size(), kDescriptorSize);
    d.flann_tree = std::make_unique<flann::KDTreeSingleIndex<flann::L2<float>>>(
        m, flann::KDTreeSingleIndexParams(10));
    d.flann_tree->buildIndex();
  }
  return *slot;
}

flann::SearchParams exact_params(bool sorted) {
  flann::SearchParams p(flann::FLANN_CHECKS_UNLIMITED, /*eps=*/0.f, sorted);
  p.cores = 1;
  return p;
}

void finish(benchmark::State& state, std::int64_t found) {
  state.SetItemsProcessed(state.iterations());  // items = queries
  state.counters["found/query"] =
      benchmark::Counter(static_cast<double>(found) / static_cast<double>(state.iterations()));
}

// ------------------------------------------------------------------ radius
void radius_flat(benchmark::State& state) {
  const Dataset& d = dataset(state.range(0));
  std::vector<std::uint32_t> out(d.data.size());
  std::uint32_t qi = 0;
  std::int64_t found = 0;
  for (auto _ : state) {
    const std::uint32_t n = d.tree.view.radius_search(d.queries[qi], kRadius * kRadius, out.data(),
                                                      static_cast<std::uint32_t>(out.size()));
    benchmark::DoNotOptimize(out.data());
    found += n;
    qi = (qi + 1) % kQueries;
  }
  finish(state, found);
}

void radius_flann(benchmark::State& state) {
  const Dataset& d = dataset(state.range(0));
  std::vector<std::vector<std::size_t>> ids;
  std::vector<std::vector<float>> d2;
  const flann::SearchParams params = exact_params(/*sorted=*/false);
  std::uint32_t qi = 0;
  std::int64_t found = 0;
  for (auto _ : state) {
    ArcDescriptor q = d.queries[qi];
    const flann::Matrix<float> qm(q.data(), 1, kDescriptorSize);
    found += d.flann_tree->radiusSearch(qm, ids, d2, kRadius * kRadius, params);
    benchmark::DoNotOptimize(ids.data());
    qi = (qi + 1) % kQueries;
  }
  finish(state, found);
}

void radius_brute(benchmark::State& state) {
  const Dataset& d = dataset(state.range(0));
  std::vector<std::uint32_t> out;
  out.reserve(d.data.size());
  std::uint32_t qi = 0;
  std::int64_t found = 0;
  for (auto _ : state) {
    test::brute_radius(d.data, d.queries[qi], kRadius * kRadius, out);
    benchmark::DoNotOptimize(out.data());
    found += static_cast<std::int64_t>(out.size());
    qi = (qi + 1) % kQueries;
  }
  finish(state, found);
}

// --------------------------------------------------------------------- knn
void knn_flat(benchmark::State& state) {
  const Dataset& d = dataset(state.range(0));
  std::uint32_t ids[kK];
  float d2[kK];
  std::uint32_t qi = 0;
  std::int64_t found = 0;
  for (auto _ : state) {
    found += d.tree.view.knn_search(d.queries[qi], kK, ids, d2);
    benchmark::DoNotOptimize(ids);
    benchmark::DoNotOptimize(d2);
    qi = (qi + 1) % kQueries;
  }
  finish(state, found);
}

void knn_flann(benchmark::State& state) {
  const Dataset& d = dataset(state.range(0));
  std::vector<std::vector<std::size_t>> ids;
  std::vector<std::vector<float>> d2;
  const flann::SearchParams params = exact_params(/*sorted=*/true);
  std::uint32_t qi = 0;
  std::int64_t found = 0;
  for (auto _ : state) {
    ArcDescriptor q = d.queries[qi];
    const flann::Matrix<float> qm(q.data(), 1, kDescriptorSize);
    found += d.flann_tree->knnSearch(qm, ids, d2, kK, params);
    benchmark::DoNotOptimize(ids.data());
    qi = (qi + 1) % kQueries;
  }
  finish(state, found);
}

void knn_brute(benchmark::State& state) {
  const Dataset& d = dataset(state.range(0));
  std::vector<std::pair<float, std::uint32_t>> out;
  std::uint32_t qi = 0;
  std::int64_t found = 0;
  for (auto _ : state) {
    test::brute_knn(d.data, d.queries[qi], kK, out);
    benchmark::DoNotOptimize(out.data());
    found += static_cast<std::int64_t>(out.size());
    qi = (qi + 1) % kQueries;
  }
  finish(state, found);
}

}  // namespace
}  // namespace kg

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("descriptors",
                              "6-D unit, 20 clusters (tests/bench/search_data.h); 1024 queries "
                              "from the same clusters; radius 0.3, k 8; exact search");
  const struct {
    const char* name;
    void (*fn)(benchmark::State&);
  } cases[] = {{"radius/flat", kg::radius_flat},   {"radius/flann", kg::radius_flann},
               {"radius/brute", kg::radius_brute}, {"knn/flat", kg::knn_flat},
               {"knn/flann", kg::knn_flann},       {"knn/brute", kg::knn_brute}};
  for (std::int64_t n : kg::kSizes) {
    for (const auto& c : cases) {
      benchmark::RegisterBenchmark(c.name, c.fn)->Arg(n)->Unit(benchmark::kMicrosecond);
    }
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
