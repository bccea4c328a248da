// keygraph build [--name NAME]... [--detector hessian|mser] [--structure 2|3|4]
//                MODEL... -o OUT.kgi
#include <cstdio>
#include <filesystem>
#include <set>

#include "build/image_io.h"
#include "build/model_builder.h"
#include "cli/commands.h"

namespace kg::cli {

int cmd_build(const Args& args) {
  std::vector<std::string> names, paths;
  std::string output;
  Params params;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const bool has_value = i + 1 < args.size();
    if (a == "--name" || a == "-o" || a == "--output" || a == "--detector" || a == "--structure") {
      if (!has_value) return fail("build: " + a + " needs a value");
      const std::string& v = args[++i];
      if (a == "--name") {
        names.push_back(v);
      } else if (a == "--detector") {
        if (v == "hessian") {
          params.keypoints.detector = KeypointDetector::kHessian;
        } else if (v == "mser") {
          params.keypoints.detector = KeypointDetector::kMser;
        } else {
          return fail("build: unknown detector '" + v + "' (hessian or mser)");
        }
      } else if (a == "--structure") {
        if (v != "2" && v != "3" && v != "4") return fail("build: --structure takes 2, 3 or 4");
        params.graph.structure = static_cast<Structure>(v[0] - '0');
      } else {
        output = v;
      }
    } else if (!a.empty() && a[0] == '-') {
      return fail("build: unknown option " + a);
    } else {
      paths.push_back(a);
    }
  }
  if (paths.empty()) return fail("build: no model images given");
  if (output.empty()) return fail("build: no output given (-o OUT.kgi)");
  if (names.size() > paths.size()) return fail("build: more --name options than model images");

  std::vector<BuiltModel> models;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < paths.size(); ++i) {
    const std::string name =
        i < names.size() ? names[i] : std::filesystem::path(paths[i]).stem().string();
    if (name.empty()) return fail("build: empty model name for " + paths[i]);
    if (!seen.insert(name).second) return fail("build: duplicate model name '" + name + "'");
    cv::Mat gray;
    Status s = load_gray(paths[i], gray);
    if (!s) return fail(s.message());
    BuiltModel model;
    s = build_model(gray, name, params, model);
    if (!s) return fail(s.message());
    std::printf("%s: %zu keypoints, %zu arcs, %llu keygraphs\n", name.c_str(), model.keypoints.size(),
                model.arcs.size(), static_cast<unsigned long long>(model.keygraphs));
    models.push_back(std::move(model));
  }
  Status s = write_index(models, params, output);
  if (!s) return fail(s.message());
  std::printf("wrote %s (%zu models)\n", output.c_str(), models.size());
  return 0;
}

}  // namespace kg::cli
