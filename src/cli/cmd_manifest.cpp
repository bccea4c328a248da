// keygraph manifest: its options are the Options table below (keygraph manifest --help).
//
// Ground-truth manifests for `keygraph eval --truth` from the real photo
// sets of ../shared/data/real (eval/real_sets.h, docs/EVAL.md). The
// manifest refers to the images where they are; the sets with models also
// get a models.json beside it (exit-sign-models.json, planar-pair-models.json).
#include <cstdio>
#include <filesystem>

#include "cli/commands.h"
#include "cli/device/options.h"
#include "eval/real_sets.h"
#include "platform/files/output_set.h"

namespace kg::cli {

int cmd_manifest(const Args& args) {
  std::string set, dir, output, split;
  Options options("manifest", "exit-signs|planar-pairs|negatives DIR -o OUT.jsonl [--split S]",
                  "Writes a ground-truth manifest for keygraph eval --truth from a real photo set\n"
                  "(docs/EVAL.md); the sets with models also get a models.json beside OUT.");
  options
      .positional("SET DIR", "the set (exit-signs, planar-pairs or negatives) and its directory",
                  [&](const std::string& v) -> std::string {
                    if (set.empty()) {
                      set = v;
                    } else if (dir.empty()) {
                      dir = v;
                    } else {
                      return "unexpected argument " + v;
                    }
                    return {};
                  })
      .text("-o, --out, --output", "OUT.jsonl", output, "the manifest to write (required)")
      .value("--split", "dev|test|model-bursts",
             "exit-signs only: that split of the set (default: all of it)",
             [&split](const std::string& v) -> std::string {
               if (v != "dev" && v != "test" && v != "model-bursts")
                 return "--split '" + v + "': not dev, test or model-bursts";
               split = v;
               return {};
             })
      .example("keygraph manifest exit-signs ../shared/data/real/exit-signs -o exit.jsonl");
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  if (set.empty() || dir.empty()) return options.usage_error("give a set and its directory");
  if (output.empty()) return options.usage_error("no output given (-o OUT.jsonl)");
  if (set != "exit-signs" && set != "planar-pairs" && set != "negatives")
    return options.usage_error("unknown set '" + set + "' (exit-signs, planar-pairs or negatives)");
  if (!split.empty() && set != "exit-signs")
    return options.usage_error("--split is for exit-signs");
  ConvertedSet converted;
  std::string models_name;
  Status s;
  if (set == "exit-signs") {
    s = convert_exit_signs(dir, output, split, converted);
    models_name = "exit-sign-models.json";
  } else if (set == "planar-pairs") {
    s = convert_planar_pairs(dir, output, converted);
    models_name = "planar-pair-models.json";
  } else if (set == "negatives") {
    s = convert_negatives(dir, output, converted);
  } else {
    return fail("manifest: unknown set '" + set + "' (exit-signs, planar-pairs or negatives)");
  }
  if (!s) return fail("manifest: " + s.message());
  // Both files, checked before either is written, then written together
  // (never over an input of the set, whole or not at all).
  const std::filesystem::path out(output);
  platform::OutputSet files(out.parent_path().string(), converted.inputs);
  const std::string models = (out.parent_path() / models_name).string();
  if (!converted.models_json.empty()) s = files.check(models);
  if (s) s = files.check(output);
  if (s && !converted.models_json.empty()) s = files.add(models, converted.models_json);
  if (s) s = files.add(output, converted.manifest);
  if (s) s = files.commit();
  if (!s) return fail("manifest: " + s.message());
  if (!converted.models_json.empty()) std::printf("wrote %s\n", models.c_str());
  std::printf("%s\nwrote %s\n", converted.summary.c_str(), output.c_str());
  return 0;
}

}  // namespace kg::cli
