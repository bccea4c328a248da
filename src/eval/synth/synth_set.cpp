#include "eval/synth/synth_set.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

#include "eval/report_io.h"
#include "eval/synth/sign_catalogue.h"
#include "platform/files/output_set.h"
#include "platform/files/regular_file.h"

namespace kg {

namespace fs = std::filesystem;

const std::vector<std::string>& synth_background_names() {
  // Photographs (no drawings, charts or calibration targets) of at least
  // 380 pixels a side.
  static const std::vector<std::string> names = {
      "aero1.jpg",  "aero3.jpg",     "apple.jpg",        "baboon.jpg",       "basketball1.png",
      "board.jpg",  "building.jpg",  "butterfly.jpg",    "box_in_scene.png", "fruits.jpg",
      "graf1.png",  "home.jpg",      "left.jpg",         "leuvenA.jpg",      "messi5.jpg",
      "orange.jpg", "pca_test1.jpg", "rubberwhale1.png", "smarties.png",     "squirrel_cls.jpg",
      "stuff.jpg",  "aloeL.jpg",     "ela_original.jpg"};
  return names;
}

namespace {

std::string two_digits(int i) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%02d", i);
  return buf;
}

std::string four_digits(int i) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%04d", i);
  return buf;
}

// Independent random state per frame: frame i is the same whatever the count.
Rng frame_rng(std::uint64_t seed, int i) {
  Rng mix(seed ^ (0xa0761d6478bd642fULL * static_cast<std::uint64_t>(i + 1)));
  return Rng(mix.next());
}

}  // namespace

Status render_synth_set(const SynthSetOptions& options, SynthManifest& manifest,
                        const SynthImageSink& sink, const ProgressFn& progress) {
  if (options.signs < 1 || options.signs > sign_catalogue_size())
    return {StatusCode::kInvalidArgument, "the catalogue has " +
                                              std::to_string(sign_catalogue_size()) +
                                              " signs; asked for " + std::to_string(options.signs)};
  if (options.frames < 1 || options.frames > 100000)
    return {StatusCode::kInvalidArgument, "frames must be in 1..100000"};
  if (!(options.sign_free_fraction >= 0 && options.sign_free_fraction <= 1))
    return {StatusCode::kInvalidArgument, "sign-free fraction must be in [0, 1]"};
  if (options.frame.width < 64 || options.frame.height < 64)
    return {StatusCode::kInvalidArgument, "frames must be at least 64x64"};
  for (const int q : {options.frame.jpeg_quality, options.range_frame.frame.jpeg_quality}) {
    if (q < 0 || q > 100) return {StatusCode::kInvalidArgument, "JPEG quality must be in 0..100"};
  }
  if (options.range &&
      !valid_range_frame_size(options.range_frame.width, options.range_frame.height))
    return {StatusCode::kInvalidArgument,
            "a range frame must be 640x480's camera scaled, 4:3 to 16:9 (640x480, 1280x720, ...)"};
  std::vector<cv::Mat> photos;
  std::vector<std::string> photo_names;
  for (const std::string& name : synth_background_names()) {
    const std::string path = options.backgrounds + "/" + name;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) continue;  // (imread would warn on stderr)
    const cv::Mat m = cv::imread(path, cv::IMREAD_COLOR);
    if (m.empty()) continue;
    photos.push_back(m);
    photo_names.push_back(name);
  }
  if (photos.size() < 2)
    return {StatusCode::kNotFound, options.backgrounds +
                                       ": fewer than 2 of opencv-doc's photos found (install "
                                       "Debian's opencv-doc package)"};
  manifest = SynthManifest{};
  manifest.seed = options.seed;
  manifest.width = options.range ? options.range_frame.width : options.frame.width;
  manifest.height = options.range ? options.range_frame.height : options.frame.height;
  std::vector<cv::Mat> signs;  // kept: every frame may show any of them
  for (int i = 0; i < options.signs; ++i) {
    SignImage s = render_sign(i, options.seed);
    SynthSign entry;
    entry.id = i;
    entry.name = s.name;
    entry.file = "signs/" + two_digits(i) + "-" + s.name + ".png";
    entry.width = s.image.cols;
    entry.height = s.image.rows;
    manifest.signs.push_back(entry);
    if (Status st = sink(entry.file, s.image); !st) return st;
    signs.push_back(s.image);
  }
  // Which frames show which sign: every sign equally often, in shuffled order.
  const int sign_free = static_cast<int>(std::lround(options.frames * options.sign_free_fraction));
  Rng order_rng(options.seed ^ 0x5eed5eed5eedULL);
  std::vector<int> content(static_cast<std::size_t>(options.frames), -1);
  for (int i = 0; i < options.frames - sign_free; ++i)
    content[static_cast<std::size_t>(i)] = i % options.signs;
  for (int i = options.frames - 1; i > 0; --i)
    std::swap(content[static_cast<std::size_t>(i)],
              content[order_rng.uniform(static_cast<std::uint32_t>(i + 1))]);
  const cv::Size size(options.frame.width, options.frame.height);
  for (int i = 0; i < options.frames; ++i) {
    Rng rng = frame_rng(options.seed, i);
    const std::size_t b = rng.uniform(static_cast<std::uint32_t>(photos.size()));
    std::size_t o = rng.uniform(static_cast<std::uint32_t>(photos.size() - 1));
    if (o >= b) ++o;  // the occluder comes from another photo
    const int sign = content[static_cast<std::size_t>(i)];
    SynthFrameEntry entry;
    entry.file = "frames/" + four_digits(i) + ".png";
    entry.background = photo_names[b];
    const cv::Mat none;
    const cv::Mat& drawn = sign >= 0 ? signs[static_cast<std::size_t>(sign)] : none;
    cv::Mat frame;
    if (options.range) {
      frame = render_range_frame(photos[b], drawn, sign, photos[o], options.range_frame, rng,
                                 entry.info);
    } else {
      const cv::Mat background = background_view(photos[b], size, rng);
      frame = render_frame(background, drawn, sign, photos[o], options.frame, rng, entry.info);
    }
    if (Status st = sink(entry.file, frame); !st) return st;
    manifest.frames.push_back(entry);
    if (progress) progress(i + 1, options.frames, {});
  }
  return Status::ok();
}

Status render_synth_set(const SynthSetOptions& options, SynthManifest& manifest,
                        SynthSetImages& images, const ProgressFn& progress) {
  images = SynthSetImages{};
  return render_synth_set(
      options, manifest,
      [&images](const std::string& file, const cv::Mat& image) {
        (file.rfind("signs/", 0) == 0 ? images.signs : images.frames).push_back(image);
        return Status::ok();
      },
      progress);
}

Status check_new_synth_directory(const std::string& directory) {
  if (directory.empty()) return {StatusCode::kInvalidArgument, "no output directory"};
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(directory, ec);
  if (fs::exists(status)) {
    if (!fs::is_directory(status))
      return {StatusCode::kInvalidArgument,
              directory + ": exists and is not a directory (synth makes a new one)"};
    if (!fs::is_empty(directory, ec))
      return {StatusCode::kInvalidArgument, directory + " exists and is not empty"};
  }
  return platform::check_output_directory(directory);
}

Status write_synth_set(const SynthSetOptions& options, const ProgressFn& progress) {
  if (Status s = check_new_synth_directory(options.directory); !s) return s;
  // Each image is staged as soon as it is rendered (memory does not grow
  // with the frames), and the whole set appears at the end, or nothing.
  platform::OutputSet out(options.directory, {});
  const auto stage = [&](const std::string& file, const cv::Mat& image) {
    return add_png(out, (fs::path(options.directory) / file).string(), image);
  };
  SynthManifest manifest;
  Status s = render_synth_set(options, manifest, stage, progress);
  if (s)
    s = out.add((fs::path(options.directory) / "manifest.txt").string(), manifest_text(manifest));
  if (s) s = out.commit();
  return s;
}

std::string manifest_text(const SynthManifest& m) {
  std::ostringstream out;
  out.precision(17);  // round trip
  out << "keygraph-synth 1\n# " << m.signs.size() << " signs, " << m.frames.size()
      << " frames; see src/eval/synth/synth_set.h for the fields\n";
  out << "seed " << m.seed << "\nframe-size " << m.width << ' ' << m.height << '\n';
  for (const SynthSign& s : m.signs)
    out << "sign " << s.id << ' ' << s.name << ' ' << s.file << ' ' << s.width << ' ' << s.height
        << '\n';
  for (const SynthFrameEntry& f : m.frames) {
    const SynthFrameInfo& i = f.info;
    out << "frame " << f.file << " background " << f.background << " sign " << i.sign;
    if (i.sign >= 0) {
      out << " corners";
      for (const Point2f& c : i.corners) out << ' ' << c.x << ' ' << c.y;
      out << " homography";
      for (const double v : i.homography) out << ' ' << v;
    }
    out << " occluded " << i.occluded << " blur " << i.blur_sigma << " motion " << i.motion_blur
        << " noise " << i.noise_sigma << " gain " << i.gain << " offset " << i.offset;
    if (i.distance > 0) out << " distance " << i.distance;
    if (i.jpeg_quality > 0) out << " jpeg " << i.jpeg_quality;
    out << '\n';
  }
  return out.str();
}

Status parse_manifest(const std::string& text, SynthManifest& out) {
  out = SynthManifest{};
  std::istringstream in(text);
  std::string line;
  int number = 0;
  bool header = false;
  const auto bad = [&number](const std::string& why) {
    return Status{StatusCode::kCorruptData, "manifest line " + std::to_string(number) + ": " + why};
  };
  while (std::getline(in, line)) {
    ++number;
    std::istringstream words(line);
    std::string key;
    if (!(words >> key) || key[0] == '#') continue;
    if (!header) {
      int version = 0;
      if (key != "keygraph-synth" || !(words >> version) || version != 1)
        return bad("expected 'keygraph-synth 1'");
      header = true;
      continue;
    }
    if (key == "seed") {
      if (!(words >> out.seed)) return bad("bad seed");
    } else if (key == "frame-size") {
      if (!(words >> out.width >> out.height) || out.width < 1 || out.height < 1)
        return bad("bad frame size");
    } else if (key == "sign") {
      SynthSign s;
      if (!(words >> s.id >> s.name >> s.file >> s.width >> s.height) ||
          s.id != static_cast<int>(out.signs.size()) || s.width < 1 || s.height < 1)
        return bad("bad sign record (ids must count from 0)");
      out.signs.push_back(s);
    } else if (key == "frame") {
      SynthFrameEntry f;
      if (!(words >> f.file)) return bad("frame without a file");
      for (std::string field; words >> field;) {
        SynthFrameInfo& i = f.info;
        bool ok = true;
        if (field == "background") {
          ok = static_cast<bool>(words >> f.background);
        } else if (field == "sign") {
          ok = static_cast<bool>(words >> i.sign) && i.sign >= -1 &&
               i.sign < static_cast<int>(out.signs.size());
        } else if (field == "corners") {
          for (Point2f& c : i.corners) ok = ok && static_cast<bool>(words >> c.x >> c.y);
        } else if (field == "homography") {
          for (double& v : i.homography)
            ok = ok && static_cast<bool>(words >> v) && std::isfinite(v);
        } else if (field == "occluded") {
          ok = static_cast<bool>(words >> i.occluded);
        } else if (field == "blur") {
          ok = static_cast<bool>(words >> i.blur_sigma);
        } else if (field == "motion") {
          ok = static_cast<bool>(words >> i.motion_blur);
        } else if (field == "noise") {
          ok = static_cast<bool>(words >> i.noise_sigma);
        } else if (field == "gain") {
          ok = static_cast<bool>(words >> i.gain);
        } else if (field == "offset") {
          ok = static_cast<bool>(words >> i.offset);
        } else if (field == "distance") {
          ok =
              static_cast<bool>(words >> i.distance) && std::isfinite(i.distance) && i.distance > 0;
        } else if (field == "jpeg") {
          ok = static_cast<bool>(words >> i.jpeg_quality) && i.jpeg_quality >= 1 &&
               i.jpeg_quality <= 100;
        } else {
          return bad("unknown field '" + field + "'");
        }
        if (!ok) return bad("bad value for " + field);
      }
      if (f.info.sign >= 0 && f.info.homography[8] == 0)
        return bad("frame with a sign but no homography");
      out.frames.push_back(f);
    } else {
      return bad("unknown record '" + key + "'");
    }
  }
  if (!header)
    return {StatusCode::kCorruptData, "manifest: empty or not a keygraph-synth manifest"};
  if (out.signs.empty()) return {StatusCode::kCorruptData, "manifest: no signs"};
  if (out.frames.empty()) return {StatusCode::kCorruptData, "manifest: no frames"};
  return Status::ok();
}

Status read_manifest(const std::string& directory, SynthManifest& out) {
  const std::string path = directory + "/manifest.txt";
  std::string text;
  Status s = platform::read_text_file(path, text, kMaxSynthManifestBytes, "a synth manifest");
  if (s.code() == StatusCode::kNotFound)
    return {StatusCode::kNotFound, path + ": no such file (not a keygraph synth directory)"};
  if (!s) return s;
  s = parse_manifest(text, out);
  if (!s) return {s.code(), path + ": " + s.message()};
  return Status::ok();
}

}  // namespace kg
