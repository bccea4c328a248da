#include "eval/synth/sign_catalogue.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "core/support/rng.h"
#include "eval/synth/sign_pictograms.h"

namespace kg {

namespace {

// Colour schemes (foreground on background, BGR) of real signs.
enum class Scheme { kExit, kFire, kInfo, kWarning, kPlain, kDark, kRoom };
// Pictograms left of the text, right of it, above it, or alone; text only.
enum class Layout { kText, kPictoLeft, kPictoRight, kPictoTop, kPicto };

struct Design {
  const char* name;
  Scheme scheme;
  Layout layout;
  std::vector<Pictogram> pictograms;
  std::vector<const char*> lines;
};

using P = Pictogram;
const std::vector<Design>& catalogue() {
  static const std::vector<Design> designs = {
      {"exit-right",
       Scheme::kExit,
       Layout::kPictoLeft,
       {P::kRunningMan, P::kDoor, P::kArrowRight},
       {}},
      {"exit-left",
       Scheme::kExit,
       Layout::kPictoRight,
       {P::kArrowLeft, P::kRunningMan, P::kDoor},
       {}},
      {"exit-text", Scheme::kExit, Layout::kText, {}, {"EXIT"}},
      {"emergency-exit",
       Scheme::kExit,
       Layout::kPictoLeft,
       {P::kRunningMan},
       {"EMERGENCY", "EXIT"}},
      {"fire-exit-up",
       Scheme::kExit,
       Layout::kPictoLeft,
       {P::kRunningMan, P::kArrowUp},
       {"FIRE EXIT"}},
      {"exit-down", Scheme::kExit, Layout::kPictoTop, {P::kArrowDown}, {"EXIT"}},
      {"first-aid", Scheme::kExit, Layout::kPictoTop, {P::kFirstAid}, {"FIRST AID"}},
      {"assembly-point", Scheme::kExit, Layout::kPictoTop, {P::kAssembly}, {"ASSEMBLY", "POINT"}},
      {"toilets", Scheme::kInfo, Layout::kPictoTop, {P::kMan, P::kWoman}, {"TOILETS"}},
      {"men", Scheme::kInfo, Layout::kPictoLeft, {P::kMan}, {"MEN"}},
      {"women", Scheme::kInfo, Layout::kPictoLeft, {P::kWoman}, {"WOMEN"}},
      {"accessible-wc", Scheme::kInfo, Layout::kPictoLeft, {P::kWheelchair}, {"WC"}},
      {"toilets-right",
       Scheme::kInfo,
       Layout::kPictoRight,
       {P::kMan, P::kWoman, P::kArrowRight},
       {}},
      {"lift", Scheme::kInfo, Layout::kPictoLeft, {P::kLift}, {"LIFT"}},
      {"information", Scheme::kInfo, Layout::kPictoTop, {P::kInfo}, {"INFORMATION"}},
      {"stairs-up", Scheme::kInfo, Layout::kPicto, {P::kStairsUp}, {}},
      {"stairs-down", Scheme::kPlain, Layout::kPictoLeft, {P::kStairsDown}, {"STAIRS"}},
      {"drinking-water", Scheme::kInfo, Layout::kPictoTop, {P::kDrinkingWater}, {"DRINKING WATER"}},
      {"cafeteria", Scheme::kDark, Layout::kPictoLeft, {P::kCup}, {"CAFETERIA"}},
      {"free-wifi", Scheme::kInfo, Layout::kPictoLeft, {P::kWifi}, {"FREE", "WI-FI"}},
      {"parking", Scheme::kInfo, Layout::kPicto, {P::kParking}, {}},
      {"fire-extinguisher",
       Scheme::kFire,
       Layout::kPictoTop,
       {P::kExtinguisher},
       {"FIRE", "EXTINGUISHER"}},
      {"fire-alarm", Scheme::kFire, Layout::kPictoLeft, {P::kBell}, {"FIRE ALARM"}},
      {"fire-point", Scheme::kFire, Layout::kPictoLeft, {P::kFlame, P::kExtinguisher}, {}},
      {"fire-door", Scheme::kInfo, Layout::kText, {}, {"FIRE DOOR", "KEEP SHUT"}},
      {"no-smoking", Scheme::kPlain, Layout::kPictoTop, {P::kNoSmoking}, {"NO SMOKING"}},
      {"no-smoking-symbol", Scheme::kPlain, Layout::kPicto, {P::kNoSmoking}, {}},
      {"no-phones", Scheme::kPlain, Layout::kPictoLeft, {P::kNoPhones}, {"SWITCH OFF", "PHONES"}},
      {"no-entry", Scheme::kPlain, Layout::kPictoLeft, {P::kNoEntry}, {"NO ENTRY"}},
      {"caution", Scheme::kWarning, Layout::kPictoLeft, {P::kWarning}, {"CAUTION"}},
      {"high-voltage",
       Scheme::kWarning,
       Layout::kPictoTop,
       {P::kHighVoltage},
       {"DANGER", "HIGH VOLTAGE"}},
      {"wet-floor", Scheme::kWarning, Layout::kPictoTop, {P::kWetFloor}, {"WET FLOOR"}},
      {"cctv", Scheme::kWarning, Layout::kPictoLeft, {P::kCamera}, {"CCTV IN", "OPERATION"}},
      {"room-101", Scheme::kRoom, Layout::kText, {}, {"ROOM 101"}},
      {"room-102", Scheme::kRoom, Layout::kText, {}, {"ROOM", "102"}},
      {"room-b204", Scheme::kDark, Layout::kText, {}, {"B-204"}},
      {"room-3-14", Scheme::kPlain, Layout::kText, {}, {"3.14"}},
      {"lab-7", Scheme::kRoom, Layout::kText, {}, {"LAB 7", "Robotics"}},
      {"office-12", Scheme::kPlain, Layout::kText, {}, {"OFFICE 12"}},
      {"meeting-room-a", Scheme::kDark, Layout::kText, {}, {"MEETING", "ROOM A"}},
      {"library", Scheme::kRoom, Layout::kText, {}, {"LIBRARY"}},
      {"kitchen", Scheme::kPlain, Layout::kPictoLeft, {P::kCup}, {"KITCHEN"}},
      {"staff-only", Scheme::kDark, Layout::kText, {}, {"STAFF ONLY"}},
      {"private", Scheme::kPlain, Layout::kText, {}, {"PRIVATE"}},
      {"push", Scheme::kRoom, Layout::kText, {}, {"PUSH"}},
      {"pull", Scheme::kDark, Layout::kText, {}, {"PULL"}},
      {"reception-right", Scheme::kRoom, Layout::kPictoRight, {P::kArrowRight}, {"RECEPTION"}},
      {"auditorium-left", Scheme::kDark, Layout::kPictoLeft, {P::kArrowLeft}, {"AUDITORIUM"}},
      {"rooms-110-130",
       Scheme::kRoom,
       Layout::kPictoRight,
       {P::kArrowUpRight},
       {"ROOMS", "110-130"}},
      {"server-room", Scheme::kWarning, Layout::kText, {}, {"SERVER ROOM", "AUTHORISED ONLY"}},
      {"storage", Scheme::kPlain, Layout::kText, {}, {"STORAGE"}},
      {"electrical-room",
       Scheme::kWarning,
       Layout::kPictoLeft,
       {P::kHighVoltage},
       {"ELECTRICAL", "ROOM"}},
      {"lecture-hall-2", Scheme::kRoom, Layout::kText, {}, {"LECTURE", "HALL 2"}},
      {"copy-room", Scheme::kDark, Layout::kText, {}, {"COPY ROOM"}},
      {"lift-stairs", Scheme::kInfo, Layout::kPictoLeft, {P::kLift, P::kStairsUp}, {}},
      {"keep-clear", Scheme::kFire, Layout::kText, {}, {"KEEP", "CLEAR"}},
      {"floor-2", Scheme::kDark, Layout::kText, {}, {"2"}},
      {"level-minus-1", Scheme::kInfo, Layout::kPictoLeft, {P::kArrowDown}, {"LEVEL -1"}},
  };
  return designs;
}

struct Colours {
  cv::Scalar fg, bg;
};

Colours colours(Scheme s, Rng& rng) {
  const auto jitter = [&rng](double v) {
    return std::clamp(v + (rng.uniform01() - 0.5) * 30, 0.0, 255.0);
  };
  const auto c = [&](double b, double g, double r) {
    return cv::Scalar(jitter(b), jitter(g), jitter(r));
  };
  switch (s) {
    case Scheme::kExit:
      return {c(245, 245, 245), c(70, 140, 20)};
    case Scheme::kFire:
      return {c(245, 245, 245), c(40, 30, 200)};
    case Scheme::kInfo:
      return {c(245, 245, 245), c(150, 80, 20)};
    case Scheme::kWarning:
      return {c(25, 25, 25), c(0, 200, 250)};
    case Scheme::kPlain:
      return {c(30, 30, 30), c(240, 240, 240)};
    case Scheme::kDark:
      return {c(240, 240, 240), c(60, 60, 60)};
    case Scheme::kRoom:
      return {c(40, 40, 40), c(215, 225, 230)};
  }
  return {c(0, 0, 0), c(255, 255, 255)};
}

const int kFonts[] = {cv::FONT_HERSHEY_SIMPLEX, cv::FONT_HERSHEY_DUPLEX, cv::FONT_HERSHEY_TRIPLEX,
                      cv::FONT_HERSHEY_COMPLEX, cv::FONT_HERSHEY_SIMPLEX | cv::FONT_ITALIC};

// Lines of text centred in `box`, at the largest scale that fits.
void draw_lines(cv::Mat& img, const std::vector<const char*>& lines, const cv::Rect& box, int font,
                double weight, const cv::Scalar& colour) {
  if (lines.empty() || box.width < 8 || box.height < 8) return;
  const int n = static_cast<int>(lines.size());
  const double gap = 0.35;  // between lines, in line heights
  double scale = 10.0;
  for (const char* line : lines) {
    int baseline = 0;
    const cv::Size s = cv::getTextSize(line, font, 1.0, 1, &baseline);
    scale = std::min(scale, 0.9 * box.width / std::max(1, s.width));
    scale = std::min(scale, 0.8 * box.height / (n * s.height + (n - 1) * gap * s.height));
  }
  const int thickness = std::max(1, cvRound(scale * weight));
  std::vector<cv::Size> sizes;
  int total = 0;
  for (const char* line : lines) {
    int baseline = 0;
    sizes.push_back(cv::getTextSize(line, font, scale, thickness, &baseline));
    total += sizes.back().height;
  }
  const int step_gap = cvRound(gap * sizes[0].height);
  total += (n - 1) * step_gap;
  int y = box.y + (box.height - total) / 2;
  for (int i = 0; i < n; ++i) {
    y += sizes[static_cast<std::size_t>(i)].height;
    const int x = box.x + (box.width - sizes[static_cast<std::size_t>(i)].width) / 2;
    cv::putText(img, lines[static_cast<std::size_t>(i)], {x, y}, font, scale, colour, thickness,
                cv::LINE_AA);
    y += step_gap;
  }
}

}  // namespace

int sign_catalogue_size() {
  return static_cast<int>(catalogue().size());
}

SignImage render_sign(int id, std::uint64_t seed) {
  SignImage out;
  if (id < 0 || id >= sign_catalogue_size()) return out;
  const Design& d = catalogue()[static_cast<std::size_t>(id)];
  out.name = d.name;
  Rng rng(seed * 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(id) * 0xd1b54a32d192ed03ULL +
          1);
  const Colours col = colours(d.scheme, rng);
  const int font = kFonts[rng.uniform(sizeof(kFonts) / sizeof(kFonts[0]))];
  const double weight = 1.6 + 1.6 * rng.uniform01();  // stroke thickness per unit of font scale
  const int pictos = static_cast<int>(d.pictograms.size());
  const int lines = static_cast<int>(d.lines.size());
  const double jitter = 0.9 + 0.2 * rng.uniform01();

  // Canvas size from the layout.
  int w = 0, h = 0;
  switch (d.layout) {
    case Layout::kText:
      w = 360;
      h = lines > 1 ? 200 : 140;
      break;
    case Layout::kPictoLeft:
    case Layout::kPictoRight:
      h = 180;
      w = 160 * pictos + (lines > 0 ? 240 : 20);
      break;
    case Layout::kPictoTop:
      w = std::max(280, 150 * pictos + 40);
      h = 200 + 55 * lines;
      break;
    case Layout::kPicto:
      w = h = 260;
      break;
  }
  w = cvRound(w * jitter);
  h = cvRound(h * (0.95 + 0.1 * rng.uniform01()));
  out.image = cv::Mat(h, w, CV_8UC3, col.bg);
  cv::Mat& img = out.image;

  // Border: none, a frame line, or a double frame, each with a margin.
  const int style = static_cast<int>(rng.uniform(3));
  const int margin = std::max(4, cvRound(std::min(w, h) * (0.03 + 0.03 * rng.uniform01())));
  const int line = std::max(2, cvRound(std::min(w, h) * 0.025));
  if (style >= 1)
    cv::rectangle(img, cv::Rect(margin, margin, w - 2 * margin, h - 2 * margin), col.fg, line,
                  cv::LINE_AA);
  if (style == 2) {
    const int m2 = margin + 2 * line;
    cv::rectangle(img, cv::Rect(m2, m2, w - 2 * m2, h - 2 * m2), col.fg, std::max(1, line / 2),
                  cv::LINE_AA);
  }
  const int inner = margin + (style >= 1 ? 3 * line : 0) + 4;
  const cv::Rect content(inner, inner, w - 2 * inner, h - 2 * inner);

  // Pictograms in a row of squares, then the text in what remains.
  const auto draw_row = [&](const cv::Rect& area) {
    if (pictos == 0) return;
    const int side = std::min(area.height, area.width / pictos);
    const int x0 = area.x + (area.width - side * pictos) / 2,
              y0 = area.y + (area.height - side) / 2;
    for (int i = 0; i < pictos; ++i) {
      const int pad = side / 14;
      draw_pictogram(img, d.pictograms[static_cast<std::size_t>(i)],
                     cv::Rect(x0 + i * side + pad, y0 + pad, side - 2 * pad, side - 2 * pad),
                     col.fg, col.bg);
    }
  };
  switch (d.layout) {
    case Layout::kText:
      draw_lines(img, d.lines, content, font, weight, col.fg);
      break;
    case Layout::kPictoLeft:
    case Layout::kPictoRight: {
      const int row =
          lines > 0 ? std::min(content.width / 2, content.height * pictos) : content.width;
      const bool left = d.layout == Layout::kPictoLeft;
      const cv::Rect picto(left ? content.x : content.x + content.width - row, content.y, row,
                           content.height);
      const cv::Rect text(left ? content.x + row : content.x, content.y, content.width - row,
                          content.height);
      draw_row(picto);
      draw_lines(img, d.lines, text, font, weight, col.fg);
      break;
    }
    case Layout::kPictoTop: {
      const int text_h = lines > 0 ? std::min(content.height / 2, 50 * lines + 10) : 0;
      draw_row(cv::Rect(content.x, content.y, content.width, content.height - text_h));
      draw_lines(img, d.lines,
                 cv::Rect(content.x, content.y + content.height - text_h, content.width, text_h),
                 font, weight, col.fg);
      break;
    }
    case Layout::kPicto:
      draw_row(content);
      break;
  }
  return out;
}

}  // namespace kg
