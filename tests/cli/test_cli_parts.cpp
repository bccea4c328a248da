// The CLI's shared parts (src/cli/device) on their own: the option parser's
// rules (a value option once unless repeatable, `--` ends the options),
// JSON strings of names that are not UTF-8, the scene error line, where a
// detection's name goes in a picture and the font that draws it, and the
// --draw plan checked before the first scene.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/device/bitmap_font.h"
#include "cli/device/draw_targets.h"
#include "cli/device/frame_output.h"
#include "cli/device/json.h"
#include "cli/device/options.h"
#include "cli/device/scene_list.h"
#include "support/temp_dir.h"

namespace kg::cli {
namespace {

namespace fs = std::filesystem;

// A table like a command's: --index once, --set repeatable, a flag,
// positional SCENE...
struct Parsed {
  std::string index;
  std::vector<std::string> sets, scenes;
  bool json = false;
  Options options{"detect", "--index I.kgi SCENE...", "test"};
  Parsed() {
    options.text("--index", "I.kgi", index, "the index")
        .value("--set", "NAME=VALUE", "a parameter",
               [this](const std::string& v) {
                 sets.push_back(v);
                 return std::string();
               })
        .repeatable()
        .flag("--json", json, "JSON")
        .positional("SCENE...", "scenes", [this](const std::string& v) {
          scenes.push_back(v);
          return std::string();
        });
  }
};

TEST(CliOptions, ValueOptionGivenTwiceIsAUsageError) {
  Parsed p;
  testing::internal::CaptureStderr();
  EXPECT_EQ(p.options.parse({"--index", "a.kgi", "--index", "b.kgi", "s.png"}), kUsageError);
  EXPECT_EQ(testing::internal::GetCapturedStderr(),
            "keygraph: detect: --index given twice (it takes one value) (see keygraph detect "
            "--help)\n");
}

TEST(CliOptions, RepeatableOptionAndRepeatedFlag) {
  Parsed p;
  EXPECT_EQ(p.options.parse({"--set", "a=1", "--json", "--set", "b=2", "--json", "s.png"}), -1);
  EXPECT_EQ(p.sets, (std::vector<std::string>{"a=1", "b=2"}));
  EXPECT_TRUE(p.json);
  EXPECT_NE(p.options.help().find("a parameter (repeatable)"), std::string::npos);
}

TEST(CliOptions, DoubleDashEndsTheOptions) {
  Parsed p;
  EXPECT_EQ(p.options.parse({"--index", "i.kgi", "--", "-scene.png", "--json", "--help", "--"}),
            -1);
  EXPECT_EQ(p.scenes, (std::vector<std::string>{"-scene.png", "--json", "--help", "--"}));
  EXPECT_FALSE(p.json);
  EXPECT_FALSE(asks_for_help({"--", "-h"}));
  EXPECT_TRUE(asks_for_help({"-h", "--"}));
  EXPECT_NE(p.options.help().find("\n  --  "), std::string::npos) << p.options.help();
}

TEST(CliJson, NamesThatAreNotUtf8StayValidJson) {
  EXPECT_EQ(json_string("caf\xc3\xa9.png"), "\"caf\xc3\xa9.png\"");     // UTF-8 kept
  EXPECT_EQ(json_string("caf\xe9.png"), "\"caf\\ufffd.png\"");          // Latin-1 byte
  EXPECT_EQ(json_string("\xc3"), "\"\\ufffd\"");                        // truncated sequence
  EXPECT_EQ(json_string("\xc0\xaf"), "\"\\ufffd\\ufffd\"");             // overlong '/'
  EXPECT_EQ(json_string("\xed\xa0\x80"), "\"\\ufffd\\ufffd\\ufffd\"");  // a surrogate
  EXPECT_EQ(json_string("\xf4\x90\x80\x80"), "\"\\ufffd\\ufffd\\ufffd\\ufffd\"");  // > U+10FFFF
  EXPECT_EQ(json_string("\xf0\x9f\x98\x80"), "\"\xf0\x9f\x98\x80\"");              // U+1F600 kept
  EXPECT_EQ(json_string("a\"b\\c\n\x01"), "\"a\\\"b\\\\c\\n\\u0001\"");
}

TEST(CliJson, SceneErrorLine) {
  EXPECT_EQ(scene_error_json("x\xff.png", "x\xff.png: no such file"),
            "{\"scene\": \"x\\ufffd.png\", \"error\": \"x\\ufffd.png: no such file\"}");
}

// live's additions (a frame without detection, a followed object) and the
// stage a time budget ran out in: where they go in the line.
TEST(CliJson, TrackFieldsAndStoppedEarly) {
  DetectionList found;
  Detection d;
  d.model_name = "box";
  d.track_id = 3;
  d.tracked = true;
  ASSERT_TRUE(found.push_back(d));
  DetectStats stats;
  const std::string plain = detection_json("f.pgm", 64, 48, 1.5, found, stats);
  EXPECT_EQ(plain.find("\"detected\""), std::string::npos);
  EXPECT_EQ(plain.find("\"track\""), std::string::npos);
  EXPECT_NE(plain.find("\"truncated\": [], \"stopped_early\": null}}"), std::string::npos) << plain;

  const TrackedFrame followed{false};
  stats.stopped_early = "selection";
  const std::string live = detection_json("f.pgm", 64, 48, 1.5, found, stats, &followed);
  EXPECT_NE(live.find("\"time_ms\": 1.5, \"detected\": false, \"detections\": ["),
            std::string::npos)
      << live;
  EXPECT_NE(live.find("\"confidence\": 0, \"track\": 3, \"tracked\": true}]"), std::string::npos)
      << live;
  EXPECT_NE(live.find("\"stopped_early\": \"selection\"}}"), std::string::npos) << live;
}

Detection detection_with_corners(Point2f a, Point2f b, Point2f c, Point2f d) {
  Detection det;
  det.corners[0] = a;
  det.corners[1] = b;
  det.corners[2] = c;
  det.corners[3] = d;
  return det;
}

// The whole text box (origin x .. x + w, y - h .. y + baseline) inside a
// width x height picture.
void expect_inside(const LabelPosition& at, int width, int height, int w, int h, int baseline) {
  EXPECT_GE(at.x, 0);
  EXPECT_LE(at.x + w, width);
  EXPECT_GE(at.y - h, 0);
  EXPECT_LE(at.y + baseline, height);
}

TEST(CliLabel, AboveTheTopmostCornerWhenThereIsRoom) {
  const Detection d = detection_with_corners({100, 100}, {200, 100}, {200, 200}, {100, 200});
  const LabelPosition at = label_position(d, 640, 480, 60, 12, 5);
  EXPECT_EQ(at.x, 100);
  EXPECT_EQ(at.y, 100 - 4 - 5);
}

TEST(CliLabel, UpsideDownAtTheBottomRightStaysInside) {
  // An upside-down object: its first corner (the model's top left) is at
  // the bottom right, at the picture's edge, where the name was clipped.
  const Detection d = detection_with_corners({639, 479}, {500, 479}, {500, 380}, {639, 380});
  const LabelPosition at = label_position(d, 640, 480, 80, 14, 6);
  expect_inside(at, 640, 480, 80, 14, 6);
  EXPECT_EQ(at.y, 380 - 4 - 6);  // above its topmost corner
}

TEST(CliLabel, AtTheTopEdgeGoesBelowAndInside) {
  const Detection d = detection_with_corners({-30, -20}, {700, -20}, {700, 100}, {-30, 100});
  const LabelPosition at = label_position(d, 640, 480, 120, 14, 6);
  expect_inside(at, 640, 480, 120, 14, 6);
}

TEST(CliLabel, WildCornersStayInside) {
  const Detection d = detection_with_corners({1e30f, -1e30f}, {5, 5}, {6, 6}, {7, 7});
  expect_inside(label_position(d, 320, 240, 50, 10, 4), 320, 240, 50, 10, 4);
}

// A gray picture of `w` x `h` in `value`.
platform::GrayImage gray_picture(int w, int h, std::uint8_t value) {
  platform::GrayImage img;
  img.width = w;
  img.height = h;
  img.pixels.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), value);
  return img;
}

std::uint8_t at(const platform::GrayImage& img, int x, int y) {
  return img.pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) +
                    static_cast<std::size_t>(x)];
}

TEST(CliFont, DrawsTheLetterItsRowsSay) {
  // 'T' in the 5 x 7 font: the top row full, then the middle column.
  platform::GrayImage img = gray_picture(20, 20, 128);
  draw_text(img, "T", 5, 12, 1, 255, 0);  // rows 5..11, columns 5..9
  for (int x = 5; x < 10; ++x) EXPECT_EQ(at(img, x, 5), 255) << x;
  for (int y = 6; y < 12; ++y) {
    EXPECT_EQ(at(img, 7, y), 255) << y;
    EXPECT_EQ(at(img, 6, y), 0) << y;  // the edge beside the stem
    if (y > 6) {                       // (row 6 is the bar's edge)
      EXPECT_EQ(at(img, 5, y), 128) << y;
    }
  }
  EXPECT_EQ(at(img, 7, 4), 0);     // the edge above the bar
  EXPECT_EQ(at(img, 7, 12), 0);    // and below the stem
  EXPECT_EQ(at(img, 0, 0), 128);   // nothing far from the text
  EXPECT_EQ(at(img, 7, 14), 128);  // nothing below the baseline's edge
}

TEST(CliFont, ScalesByWholePixelsAndMeasuresItsWidth) {
  EXPECT_EQ(text_width("", 2), 0);
  EXPECT_EQ(text_width("box", 1), 17);  // 3 letters of 5, 2 columns between
  EXPECT_EQ(text_width("box", 2), 34);
  platform::GrayImage img = gray_picture(40, 30, 128);
  draw_text(img, "I", 10, 24, 2, 255, 0);  // 'I': its top row spans columns 1..3
  for (int y = 10; y < 12; ++y) {
    for (int x = 12; x < 18; ++x) EXPECT_EQ(at(img, x, y), 255) << x << "," << y;
  }
  EXPECT_EQ(at(img, 10, 10), 128);  // column 0 of the glyph is empty, its edge 1 px wide
}

TEST(CliFont, TextPartlyOrWhollyOutsideIsClipped) {
  platform::GrayImage img = gray_picture(16, 10, 128);
  // AddressSanitizer and the pixel counts check that nothing lands outside.
  draw_text(img, "EXIT", -7, 8, 1, 255, 0);
  draw_text(img, "EXIT", 12, 3, 3, 255, 0);
  draw_text(img, "far", -100000, -100000, 2, 255, 0);
  draw_text(img, "far", 1 << 29, 1 << 29, 4, 255, 0);
  draw_text(img, "\xc3\xa9\x01", 2, 9, 1, 255, 0);  // non-ASCII bytes: boxes
  int white = 0;
  for (const std::uint8_t v : img.pixels) white += v == 255;
  EXPECT_GT(white, 10);
  EXPECT_LT(white, 16 * 10);
}

TEST(CliFont, DrawnPicturesCarryTheModelName) {
  const Detection box = [] {
    Detection d = detection_with_corners({100, 100}, {300, 100}, {300, 250}, {100, 250});
    d.model_name = "box";
    return d;
  }();
  DetectionList found;
  found.push_back(box);
  const platform::GrayImage frame = gray_picture(640, 480, 128);
  platform::GrayImage drawn;
  draw_outlines(ImageView{frame.pixels.data(), frame.width, frame.height, frame.width}, found,
                drawn);
  // The name at twice the font's size above the top-left corner: "box" is
  // 34 x 14 pixels with its baseline 4 pixels above the corner.
  int white = 0;
  for (int y = 100 - 4 - 14; y < 100 - 4; ++y) {
    for (int x = 100; x < 134; ++x) white += at(drawn, x, y) == 255;
  }
  EXPECT_GT(white, 60);
  EXPECT_EQ(at(drawn, 200, 180), 128);  // inside the outline: the frame untouched
}

class CliDrawPlan : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = tmp_.path();
    fs::create_directories(dir_ / "photos");
    fs::create_directories(dir_ / "out");
    for (const char* name : {"photos/a.jpg", "photos/b.png", "photos/notes.txt"})
      std::ofstream(dir_ / name) << "x";
  }
  std::string plan(const std::string& draw, const std::vector<std::string>& scenes,
                   std::vector<std::string>& out) {
    const auto png_only = [](const std::string& p) { return fs::path(p).extension() == ".png"; };
    std::vector<std::string> inputs = scenes;
    return plan_drawings(draw, scenes, ".png", png_only, inputs, out);
  }
  std::string p(const char* rel) const { return (dir_ / rel).string(); }
  test::TempDir tmp_;
  fs::path dir_;
};

TEST_F(CliDrawPlan, DirectoryGivesOnePicturePerScene) {
  std::vector<std::string> out;
  EXPECT_EQ(plan(p("out"), {p("photos/a.jpg"), p("photos/b.png")}, out), "");
  EXPECT_EQ(out, (std::vector<std::string>{p("out/a.png"), p("out/b.png")}));
  EXPECT_EQ(plan(p("out") + "/", {p("photos/a.jpg")}, out), "");
  EXPECT_EQ(out, (std::vector<std::string>{p("out/a.png")}));
  // Nothing was left behind by the checks.
  EXPECT_TRUE(fs::is_empty(dir_ / "out"));
}

TEST_F(CliDrawPlan, FileNameKeepsTheOlderSpelling) {
  std::vector<std::string> out;
  EXPECT_EQ(plan(p("found.png"), {p("photos/a.jpg")}, out), "");
  EXPECT_EQ(out, (std::vector<std::string>{p("found.png")}));
  EXPECT_EQ(plan(p("found.png"), {p("photos/a.jpg"), p("photos/b.png")}, out), "");
  EXPECT_EQ(out, (std::vector<std::string>{p("found_a.png"), p("found_b.png")}));
}

TEST_F(CliDrawPlan, BadTargetsFailBeforeAnyScene) {
  std::vector<std::string> out;
  EXPECT_NE(plan(p("missing/x.png"), {p("photos/a.jpg")}, out), "");
  EXPECT_NE(plan(p("missing/"), {p("photos/a.jpg")}, out).find("no such directory"),
            std::string::npos);
  EXPECT_NE(plan(p("noext"), {p("photos/a.jpg")}, out).find("no picture extension"),
            std::string::npos);
  EXPECT_NE(plan(p("x.bmp"), {p("photos/a.jpg")}, out).find("cannot write"), std::string::npos);
  // A scene as its own picture: refused, the scene untouched.
  EXPECT_NE(plan(p("photos/b.png"), {p("photos/b.png")}, out), "");
  EXPECT_NE(plan(p("photos"), {p("photos/b.png")}, out), "");
  // Two scenes with one stem into one directory.
  fs::create_directories(dir_ / "more");
  std::ofstream(dir_ / "more/a.png") << "x";
  EXPECT_NE(plan(p("out"), {p("photos/a.jpg"), p("more/a.png")}, out).find("would both be drawn"),
            std::string::npos);
  EXPECT_EQ(std::ifstream(p("photos/b.png")).get(), 'x');
}

TEST_F(CliDrawPlan, ScenesFromADirectory) {
  std::vector<std::string> scenes;
  EXPECT_EQ(expand_scene_paths({p("photos"), p("photos/a.jpg")}, scenes), "");
  EXPECT_EQ(scenes,
            (std::vector<std::string>{p("photos/a.jpg"), p("photos/b.png"), p("photos/a.jpg")}));
  EXPECT_NE(expand_scene_paths({p("out")}, scenes).find("no image files"), std::string::npos);
}

}  // namespace
}  // namespace kg::cli
