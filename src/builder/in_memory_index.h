// An in-memory model index (evaluations, the quality report): built models serialised and
// viewed from 64-byte-aligned storage, as a mapped .kgi file would be.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "builder/index_writer.h"
#include "keygraph/model_index.h"

namespace kg {

// Copies `bytes` (a serialised index) into 64-byte aligned storage, which
// `storage` then owns, and views it as `out` (ModelIndex::view's alignment
// rule); `out` is valid while `storage` lives.
Status view_aligned_copy(const std::vector<std::uint8_t>& bytes,
                         std::unique_ptr<std::uint8_t[]>& storage, ModelIndex& out);

class InMemoryIndex {
 public:
  Status build(const std::vector<BuiltModel>& models, const Params& params);
  const ModelIndex& index() const { return index_; }

 private:
  std::unique_ptr<std::uint8_t[]> storage_;
  ModelIndex index_;
};

}  // namespace kg
