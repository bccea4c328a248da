// kg_index: an index opened from a file or caller memory, with its model
// names as NUL-terminated strings.
#include <cstring>
#include <new>
#include <string>

#include "capi/handles.h"

namespace {

using kg::capi::fail;

// Moves `opened` into a new handle with its name table; KG_OK and `out`,
// or an error and `out` untouched.
kg_status adopt(kg::ModelIndex&& opened, kg_index** out) {
  std::unique_ptr<kg_index> handle(new (std::nothrow) kg_index);
  if (!handle) return fail(KG_RESOURCE_EXHAUSTED, "out of memory for the index handle");
  handle->index = std::move(opened);
  const kg::ModelIndex& index = handle->index;
  const auto models = static_cast<std::size_t>(index.model_count());
  std::size_t bytes = 0;
  for (int m = 0; m < index.model_count(); ++m) bytes += index.model(m).name.size() + 1;
  handle->name_bytes.reset(new (std::nothrow) char[bytes == 0 ? 1 : bytes]);
  handle->names.reset(new (std::nothrow) const char*[models == 0 ? 1 : models]);
  if (!handle->name_bytes || !handle->names)
    return fail(KG_RESOURCE_EXHAUSTED, "out of memory for the index's model names");
  char* next = handle->name_bytes.get();
  for (int m = 0; m < index.model_count(); ++m) {
    const std::string_view name = index.model(m).name;
    std::memcpy(next, name.data(), name.size());
    next[name.size()] = '\0';
    handle->names[m] = next;
    next += name.size() + 1;
  }
  *out = handle.release();
  return KG_OK;
}

using Opener = kg::Status (*)(const std::string&, kg::ModelIndex&);

kg_status open_with(Opener opener, const char* path, kg_index** out) {
  if (out == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_index_open: out is NULL");
  *out = nullptr;
  if (path == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_index_open: path is NULL");
  kg::ModelIndex index;
  if (kg::Status s = opener(path, index); !s) return fail(s);
  return adopt(std::move(index), out);
}

}  // namespace

extern "C" {

kg_status kg_index_open(const char* path, kg_index** out) {
  return open_with(&kg::ModelIndex::open, path, out);
}

kg_status kg_index_read(const char* path, kg_index** out) {
  return open_with(&kg::ModelIndex::read, path, out);
}

kg_status kg_index_from_memory(const void* data, size_t size, kg_index** out) {
  if (out == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_index_from_memory: out is NULL");
  *out = nullptr;
  if (data == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_index_from_memory: data is NULL");
  kg::ModelIndex index;
  if (kg::Status s = kg::ModelIndex::view(static_cast<const std::uint8_t*>(data), size, index); !s)
    return fail(s);
  return adopt(std::move(index), out);
}

void kg_index_destroy(kg_index* index) {
  delete index;
}

kg_status kg_index_version(const kg_index* index, int* major, int* minor) {
  if (index == nullptr || major == nullptr || minor == nullptr)
    return fail(KG_INVALID_ARGUMENT, "kg_index_version: NULL argument");
  *major = index->index.version_major();
  *minor = index->index.version_minor();
  return KG_OK;
}

int kg_index_model_count(const kg_index* index) {
  return index == nullptr ? 0 : index->index.model_count();
}

const char* kg_index_model_name(const kg_index* index, int model) {
  if (index == nullptr || model < 0 || model >= index->index.model_count()) return nullptr;
  return index->names[model];
}

kg_status kg_index_model_info(const kg_index* index, int model, kg_model_info* out) {
  if (index == nullptr || out == nullptr)
    return fail(KG_INVALID_ARGUMENT, "kg_index_model_info: NULL argument");
  if (model < 0 || model >= index->index.model_count())
    return fail(KG_INVALID_ARGUMENT, "kg_index_model_info: no such model in the index");
  const kg::ModelInfo info = index->index.model(model);
  out->name = index->names[model];
  out->width = info.width;
  out->height = info.height;
  for (int c = 0; c < 4; ++c) {
    out->outline[c][0] = info.outline[c].x;
    out->outline[c][1] = info.outline[c].y;
  }
  out->keypoints = info.keypoint_count;
  return KG_OK;
}

}  // extern "C"
