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
#include "eval/report_io.h"

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
      .text("--split", "dev|test|model-bursts", split,
            "exit-signs only: that split of the set (default: all of it)")
      .example("keygraph manifest exit-signs ../shared/data/real/exit-signs -o exit.jsonl");
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  if (set.empty() || dir.empty()) return options.usage_error("give a set and its directory");
  if (output.empty()) return options.usage_error("no output given (-o OUT.jsonl)");
  if (set != "exit-signs" && set != "planar-pairs" && set != "negatives")
    return options.usage_error("unknown set '" + set + "' (exit-signs, planar-pairs or negatives)");
  if (!split.empty() && set != "exit-signs")
    return options.usage_error("--split is for exit-signs");
  if (!split.empty() && split != "dev" && split != "test" && split != "model-bursts")
    return options.usage_error("--split takes dev, test or model-bursts, got '" + split + "'");
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
  const std::filesystem::path out(output);
  if (!converted.models_json.empty()) {
    const std::string models = (out.parent_path() / models_name).string();
    if (s = write_text_file(models, converted.models_json); !s)
      return fail("manifest: " + s.message());
    std::printf("wrote %s\n", models.c_str());
  }
  if (s = write_text_file(output, converted.manifest); !s) return fail("manifest: " + s.message());
  std::printf("%s\nwrote %s\n", converted.summary.c_str(), output.c_str());
  return 0;
}

}  // namespace kg::cli
