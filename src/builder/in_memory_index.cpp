#include "builder/in_memory_index.h"

#include <cstring>

namespace kg {

Status view_aligned_copy(const std::vector<std::uint8_t>& bytes,
                         std::unique_ptr<std::uint8_t[]>& storage, ModelIndex& out) {
  storage.reset(new std::uint8_t[bytes.size() + 64]);
  const auto misalign = reinterpret_cast<std::uintptr_t>(storage.get()) % 64;
  std::uint8_t* aligned = storage.get() + (64 - misalign) % 64;
  std::memcpy(aligned, bytes.data(), bytes.size());
  return ModelIndex::view(aligned, bytes.size(), out);
}

Status InMemoryIndex::build(const std::vector<BuiltModel>& models, const Params& params) {
  std::vector<std::uint8_t> bytes;
  if (Status s = serialize_index(models, params, bytes); !s) return s;
  return view_aligned_copy(bytes, storage_, index_);
}

}  // namespace kg
