// The index writer: built models (builder/model_builder.h) serialised into
// the .kgi layout that core/index/model_index.cpp reads (docs/FORMAT.md;
// the section ids and record layouts both sides share are in
// core/index/index_format.h). The only code that writes indexes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "builder/model_builder.h"
#include "keygraph/model_index.h"
#include "keygraph/params.h"
#include "keygraph/status.h"

namespace kg {

namespace platform {
class OutputFile;
}  // namespace platform

// The quality report of an index's models (format sections 12-14;
// builder/model_quality.h measures it): one record per model, the views of
// all models consecutive, look-alike pairs sorted.
struct QualityReport {
  std::vector<ModelQuality> models;
  std::vector<ViewQuality> views;
  std::vector<LookAlike> look_alikes;
};

// Serialises models into the .kgi layout (docs/FORMAT.md). Deterministic.
// Without `quality` the quality sections are written empty (no report).
Status serialize_index(const std::vector<BuiltModel>& models, const Params& params,
                       std::vector<std::uint8_t>& bytes, const QualityReport* quality = nullptr);

// Writes the index to `path` through a platform::OutputFile
// (platform/files/output_file.h): a unique temporary renamed into place, so
// a failure or an interrupt never leaves a partial index behind, and never
// over anything but a regular file.
Status write_index(const std::vector<BuiltModel>& models, const Params& params,
                   const std::string& path, const QualityReport* quality = nullptr);
// The same into an output created beforehand (e.g. before a long build, so
// that a bad output path fails at once); commits it.
Status write_index(const std::vector<BuiltModel>& models, const Params& params,
                   platform::OutputFile& out, const QualityReport* quality = nullptr);

}  // namespace kg
