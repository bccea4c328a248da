#include "eval/repeatability_report.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace kg {

namespace {

double ratio(double a, double b) {
  return b > 0 ? a / b : 0.0;
}

void add(PairRepeatability& sum, const PairRepeatability& c) {
  sum.model_keypoints += c.model_keypoints;
  sum.scene_keypoints += c.scene_keypoints;
  sum.model_inside += c.model_inside;
  sum.model_repeated += c.model_repeated;
  sum.model_inside_shifted += c.model_inside_shifted;
  sum.model_repeated_shifted += c.model_repeated_shifted;
  sum.sampled += c.sampled;
  sum.sampled_inside += c.sampled_inside;
  sum.sampled_repeated += c.sampled_repeated;
  sum.sampled_repeated_shifted += c.sampled_repeated_shifted;
  sum.triangles_keygraph_shifted += c.triangles_keygraph_shifted;
  sum.triangles += c.triangles;
  sum.triangles_repeated += c.triangles_repeated;
  sum.triangles_keygraph += c.triangles_keygraph;
}

std::string format(const char* f, double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::vector<std::string> subsets_of(const std::vector<RepeatabilityCase>& cases) {
  std::vector<std::string> out;
  for (const RepeatabilityCase& c : cases) {
    if (std::find(out.begin(), out.end(), c.subset) == out.end()) out.push_back(c.subset);
  }
  return out;
}

int label_width(const RepeatabilityOptions& options) {
  std::size_t w = 8;
  for (const RepeatabilityDetector& d : options.detectors) w = std::max(w, d.label.size());
  return static_cast<int>(w);
}

// A row: the label left-aligned in `width`, then the cells right-aligned in 8.
std::string row(const std::string& label, int width, const std::vector<std::string>& cells) {
  std::string out = label;
  out.resize(static_cast<std::size_t>(width), ' ');
  for (const std::string& c : cells) {
    out += std::string(c.size() < 8 ? 8 - c.size() : 1, ' ');
    out += c;
  }
  return out + '\n';
}

}  // namespace

double RepeatabilityTally::repeatability() const {
  return ratio(counts.model_repeated, counts.model_inside);
}
double RepeatabilityTally::chance() const {
  return ratio(counts.model_repeated_shifted, counts.model_inside_shifted);
}
double RepeatabilityTally::keypoints_per_image() const {
  return ratio(static_cast<double>(keypoints), images);
}
double RepeatabilityTally::sampled_per_image() const {
  return ratio(counts.sampled, pairs);
}
double RepeatabilityTally::sampled_repeatability() const {
  return ratio(counts.sampled_repeated, counts.sampled_inside);
}
double RepeatabilityTally::sampled_chance() const {
  return ratio(counts.sampled_repeated_shifted, counts.sampled_inside);
}
double RepeatabilityTally::chance_keygraphs_per_image() const {
  return ratio(counts.triangles_keygraph_shifted, pairs);
}
double RepeatabilityTally::triangles_repeated() const {
  return ratio(counts.triangles_repeated, counts.triangles);
}
double RepeatabilityTally::triangles_keygraph() const {
  return ratio(counts.triangles_keygraph, counts.triangles);
}
double RepeatabilityTally::keygraphs_per_image() const {
  return ratio(counts.triangles_keygraph, pairs);
}
double RepeatabilityTally::ms_per_image() const {
  return ratio(ms, images);
}
double RepeatabilityTally::ms_per_megapixel() const {
  return ratio(ms, static_cast<double>(pixels) / 1e6);
}

RepeatabilityTally tally_repeatability(const std::vector<RepeatabilityCase>& cases,
                                       const std::vector<DetectionTiming>& timings,
                                       const std::string& detector, const std::string& subset,
                                       int degree) {
  RepeatabilityTally t;
  for (const RepeatabilityCase& c : cases) {
    if (c.detector != detector || (!subset.empty() && c.subset != subset) ||
        (degree != 0 && c.degree != degree))
      continue;
    add(t.counts, c.counts);
    ++t.pairs;
  }
  for (const DetectionTiming& d : timings) {
    if (d.detector != detector || (!subset.empty() && d.subset != subset)) continue;
    ++t.images;
    t.keypoints += d.keypoints;
    t.pixels += d.pixels;
    t.ms += d.ms;
  }
  return t;
}

std::string repeatability_text(const std::vector<RepeatabilityCase>& cases,
                               const std::vector<DetectionTiming>& timings,
                               const RepeatabilityOptions& options) {
  const int width = label_width(options);
  const std::vector<std::string> subsets = subsets_of(cases);
  std::ostringstream out;
  char head[160];
  std::snprintf(head, sizeof head,
                "Repeatability: model (img1) keypoints projecting inside the scene that have a "
                "scene keypoint within %.3g px.\n",
                options.tolerance);
  out << head;
  const std::vector<std::string> degrees = {"img2", "img3", "img4", "img5", "img6"};

  for (const std::string& subset : subsets) {
    out << "\n" << subset << "\n";
    std::vector<std::string> h = degrees;
    h.insert(h.end(), {"all", "kp/img", "kg/img"});
    out << row("detector", width, h);
    for (const RepeatabilityDetector& d : options.detectors) {
      std::vector<std::string> cells;
      for (int n = 2; n <= 6; ++n)
        cells.push_back(format(
            "%.3f", tally_repeatability(cases, timings, d.label, subset, n).repeatability()));
      const RepeatabilityTally all = tally_repeatability(cases, timings, d.label, subset, 0);
      cells.push_back(format("%.3f", all.repeatability()));
      cells.push_back(format("%.0f", all.keypoints_per_image()));
      cells.push_back(format("%.0f", all.keygraphs_per_image()));
      out << row(d.label, width, cells);
    }
  }

  char title[120];
  std::snprintf(title, sizeof title, "\noverall: repeatability (%d subsets, %d pairs each)\n",
                static_cast<int>(subsets.size()), static_cast<int>(subsets.size()) * 5);
  out << title;
  std::vector<std::string> h = degrees;
  h.insert(h.end(), {"all", "chance", "all^3"});
  out << row("detector", width, h);
  for (const RepeatabilityDetector& d : options.detectors) {
    std::vector<std::string> cells;
    for (int n = 2; n <= 6; ++n)
      cells.push_back(
          format("%.3f", tally_repeatability(cases, timings, d.label, "", n).repeatability()));
    const RepeatabilityTally all = tally_repeatability(cases, timings, d.label, "", 0);
    const double r = all.repeatability();
    cells.push_back(format("%.3f", r));
    cells.push_back(format("%.3f", all.chance()));
    cells.push_back(format("%.3f", r * r * r));
    out << row(d.label, width, cells);
  }

  out << "\noverall: density, scene triangles, detection time\n";
  out << row("detector", width,
             {"kp/img", "smp/img", "smp-rep", "chance", "tri-rep", "tri-kg", "kg/img", "chance",
              "ms/img", "ms/MP"});
  for (const RepeatabilityDetector& d : options.detectors) {
    const RepeatabilityTally all = tally_repeatability(cases, timings, d.label, "", 0);
    out << row(d.label, width,
               {format("%.0f", all.keypoints_per_image()), format("%.0f", all.sampled_per_image()),
                format("%.3f", all.sampled_repeatability()), format("%.3f", all.sampled_chance()),
                format("%.3f", all.triangles_repeated()), format("%.3f", all.triangles_keygraph()),
                format("%.0f", all.keygraphs_per_image()),
                format("%.0f", all.chance_keygraphs_per_image()),
                format("%.1f", all.ms_per_image()), format("%.1f", all.ms_per_megapixel())});
  }
  out << "\nkp/img: keypoints per image (img1..img6); chance: the column before it with the\n"
         "projection (or the scene keypoint) shifted 15 px in x and y; smp: scene keypoints after\n"
         "strongest-first sampling (Chebyshev, graph.scene_sample_distance), smp-rep the fraction\n"
         "of those in view with a projected model keypoint in tolerance; tri-rep: Delaunay\n"
         "triangles of the sampled keypoints in view with all three vertices repeated; tri-kg: of\n"
         "all in view, those whose model counterparts are also pairwise model arcs (a correct\n"
         "keygraph is possible); kg/img: tri-kg triangles per scene image; ms: detection alone,\n"
         "steady clock.\n";
  return out.str();
}

std::string repeatability_csv(const std::vector<RepeatabilityCase>& cases,
                              const std::vector<DetectionTiming>& timings) {
  const auto ms_of = [&](const RepeatabilityCase& c, int image) {
    for (const DetectionTiming& t : timings) {
      if (t.detector == c.detector && t.subset == c.subset && t.image == image) return t.ms;
    }
    return 0.0;
  };
  std::ostringstream out;
  out << "detector,subset,degree,model_keypoints,scene_keypoints,model_inside,model_repeated,"
         "model_inside_shifted,model_repeated_shifted,sampled,sampled_inside,sampled_repeated,"
         "sampled_repeated_shifted,triangles,triangles_repeated,triangles_keygraph,"
         "triangles_keygraph_shifted,model_ms,scene_ms\n";
  for (const RepeatabilityCase& c : cases) {
    const PairRepeatability& r = c.counts;
    // Labels may hold ':' and '=' but no comma (commas separate detectors).
    out << c.detector << ',' << c.subset << ',' << c.degree << ',' << r.model_keypoints << ','
        << r.scene_keypoints << ',' << r.model_inside << ',' << r.model_repeated << ','
        << r.model_inside_shifted << ',' << r.model_repeated_shifted << ',' << r.sampled << ','
        << r.sampled_inside << ',' << r.sampled_repeated << ',' << r.sampled_repeated_shifted << ','
        << r.triangles << ',' << r.triangles_repeated << ',' << r.triangles_keygraph << ','
        << r.triangles_keygraph_shifted << ',' << ms_of(c, 1) << ',' << ms_of(c, c.degree) << '\n';
  }
  return out.str();
}

}  // namespace kg
