#include "eval/quad_geometry.h"

#include <algorithm>
#include <cmath>

namespace kg {

namespace {

struct Vec {
  double x, y;
};

double cross(Vec o, Vec a, Vec b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Up to 7 vertices: a triangle clipped by three half-planes.
struct Polygon {
  Vec v[9];
  int n = 0;
};

double area(const Polygon& p) {
  double s = 0;
  for (int i = 0; i < p.n; ++i) {
    const Vec a = p.v[i], b = p.v[(i + 1) % p.n];
    s += a.x * b.y - b.x * a.y;
  }
  return std::abs(s) / 2;
}

// Sutherland-Hodgman: `subject` clipped by the convex, counter-clockwise
// triangle `clip`.
Polygon clip_by_triangle(Polygon subject, const Vec (&clip)[3]) {
  for (int e = 0; e < 3 && subject.n > 0; ++e) {
    const Vec a = clip[e], b = clip[(e + 1) % 3];
    Polygon out;
    for (int i = 0; i < subject.n; ++i) {
      const Vec p = subject.v[i], q = subject.v[(i + 1) % subject.n];
      const double dp = cross(a, b, p), dq = cross(a, b, q);
      if (dp >= 0) out.v[out.n++] = p;
      if ((dp >= 0) != (dq >= 0)) {
        const double t = dp / (dp - dq);
        out.v[out.n++] = {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};
      }
    }
    subject = out;
  }
  return subject;
}

bool segments_cross(Vec a, Vec b, Vec c, Vec d) {
  const double d1 = cross(a, b, c), d2 = cross(a, b, d), d3 = cross(c, d, a), d4 = cross(c, d, b);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

// A simple quadrilateral as two counter-clockwise triangles with disjoint
// interiors: cut along the diagonal that lies inside it.
void triangulate(const Point2f (&q)[4], Vec (&t)[2][3]) {
  Vec v[4];
  for (int i = 0; i < 4; ++i) v[i] = {q[i].x, q[i].y};
  if (signed_area(q) < 0) std::swap(v[1], v[3]);  // counter-clockwise
  // The diagonal 0-2 is inside unless 1 or 3 is a reflex corner.
  const bool reflex_1_or_3 = cross(v[0], v[1], v[2]) <= 0 || cross(v[2], v[3], v[0]) <= 0;
  const int s = reflex_1_or_3 ? 1 : 0;
  const Vec a = v[s], b = v[s + 1], c = v[(s + 2) % 4], d = v[(s + 3) % 4];
  t[0][0] = a, t[0][1] = b, t[0][2] = c;
  t[1][0] = c, t[1][1] = d, t[1][2] = a;
}

}  // namespace

double order_free_corner_error(const Point2f (&a)[4], const Point2f (&b)[4]) {
  double best = INFINITY;
  for (int direction = 0; direction < 2; ++direction) {
    for (int shift = 0; shift < 4; ++shift) {
      double worst = 0;
      for (int i = 0; i < 4; ++i) {
        const int j = direction == 0 ? (i + shift) % 4 : (shift - i + 4) % 4;
        const double e = std::hypot(double{a[i].x} - b[j].x, double{a[i].y} - b[j].y);
        worst = std::isnan(e) ? INFINITY : std::max(worst, e);
      }
      best = std::min(best, worst);
    }
  }
  return best;
}

double signed_area(const Point2f (&q)[4]) {
  double s = 0;
  for (int i = 0; i < 4; ++i) {
    const Point2f& a = q[i];
    const Point2f& b = q[(i + 1) % 4];
    s += double{a.x} * b.y - double{b.x} * a.y;
  }
  return s / 2;
}

bool is_simple_quad(const Point2f (&q)[4]) {
  for (const Point2f& p : q) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) return false;
  }
  Vec v[4];
  for (int i = 0; i < 4; ++i) v[i] = {q[i].x, q[i].y};
  // Opposite sides must not cross (a bow-tie), no corner may sit on the
  // line through its neighbours, and the area must be positive.
  if (segments_cross(v[0], v[1], v[2], v[3]) || segments_cross(v[1], v[2], v[3], v[0]))
    return false;
  for (int i = 0; i < 4; ++i) {
    if (cross(v[(i + 3) % 4], v[i], v[(i + 1) % 4]) == 0) return false;
  }
  return std::abs(signed_area(q)) > 1e-9;
}

double quad_iou(const Point2f (&a)[4], const Point2f (&b)[4]) {
  if (!is_simple_quad(a) || !is_simple_quad(b)) return 0;
  Vec ta[2][3], tb[2][3];
  triangulate(a, ta);
  triangulate(b, tb);
  double inter = 0;
  for (const auto& s : ta) {
    for (const auto& c : tb) {
      Polygon p;
      p.n = 3;
      for (int i = 0; i < 3; ++i) p.v[i] = s[i];
      inter += area(clip_by_triangle(p, c));
    }
  }
  const double uni = std::abs(signed_area(a)) + std::abs(signed_area(b)) - inter;
  return uni > 0 ? std::clamp(inter / uni, 0.0, 1.0) : 0.0;
}

double longest_side(const Point2f (&q)[4]) {
  double best = 0;
  for (int i = 0; i < 4; ++i) {
    const Point2f& a = q[i];
    const Point2f& b = q[(i + 1) % 4];
    best = std::max(best, std::hypot(double{a.x} - b.x, double{a.y} - b.y));
  }
  return best;
}

namespace {

double determinant(const Homography& h) {
  return h[0] * (h[4] * h[8] - h[5] * h[7]) - h[1] * (h[3] * h[8] - h[5] * h[6]) +
         h[2] * (h[3] * h[7] - h[4] * h[6]);
}

bool finite_and_invertible(const Homography& h) {
  for (const double v : h) {
    if (!std::isfinite(v)) return false;
  }
  const double det = determinant(h);
  return std::isfinite(det) && det != 0;
}

}  // namespace

bool normalise_homography(Homography& h) {
  if (!finite_and_invertible(h) || h[8] == 0) return false;
  const double h33 = h[8];
  for (double& v : h) v /= h33;
  return finite_and_invertible(h);
}

}  // namespace kg
