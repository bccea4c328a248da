#include "builder/in_memory_index.h"

#include <cstring>

namespace kg {

Status InMemoryIndex::build(const std::vector<BuiltModel>& models, const Params& params) {
  std::vector<std::uint8_t> bytes;
  Status s = serialize_index(models, params, bytes);
  if (!s) return s;
  storage_.reset(new std::uint8_t[bytes.size() + 64]);
  const auto misalign = reinterpret_cast<std::uintptr_t>(storage_.get()) % 64;
  std::uint8_t* aligned = storage_.get() + (64 - misalign) % 64;
  std::memcpy(aligned, bytes.data(), bytes.size());
  return ModelIndex::view(aligned, bytes.size(), index_);
}

}  // namespace kg
