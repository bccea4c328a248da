// Order-free corner errors and quadrilateral IoU (eval/quad_geometry.h) on
// quadrilaterals with known answers, every corner order, degenerate and
// non-convex shapes, and a rasterised reference.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "eval/quad_geometry.h"

namespace kg {
namespace {

using Quad = Point2f[4];

void copy(const Quad& from, Quad& to) {
  for (int i = 0; i < 4; ++i) to[i] = from[i];
}

// The 8 ways to list a quadrilateral's corners: 4 starts x 2 directions.
void reorder(const Quad& q, int order, Quad& out) {
  const int shift = order % 4;
  for (int i = 0; i < 4; ++i) out[i] = q[order < 4 ? (i + shift) % 4 : (shift - i + 4) % 4];
}

// Even-odd point-in-polygon over a fine grid: an independent reference.
double raster_iou(const Quad& a, const Quad& b, double lo, double hi, int steps) {
  auto inside = [](const Quad& q, double x, double y) {
    bool in = false;
    for (int i = 0, j = 3; i < 4; j = i++) {
      if ((q[i].y > y) != (q[j].y > y) &&
          x < (q[j].x - q[i].x) * (y - q[i].y) / (q[j].y - q[i].y) + q[i].x)
        in = !in;
    }
    return in;
  };
  long inter = 0, uni = 0;
  const double step = (hi - lo) / steps;
  for (int j = 0; j < steps; ++j) {
    for (int i = 0; i < steps; ++i) {
      const double x = lo + (i + 0.5) * step, y = lo + (j + 0.5) * step;
      const bool ia = inside(a, x, y), ib = inside(b, x, y);
      inter += ia && ib;
      uni += ia || ib;
    }
  }
  return uni > 0 ? static_cast<double>(inter) / static_cast<double>(uni) : 0;
}

const Quad kSquare = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};
// An arrowhead: its reflex corner (1, 2) points into the square.
const Quad kDart = {{0, 0}, {4, 2}, {0, 4}, {1, 2}};

TEST(OrderFreeCornerError, EveryOrderOfTheSameCornersIsZero) {
  for (int order = 0; order < 8; ++order) {
    Quad q;
    reorder(kSquare, order, q);
    EXPECT_EQ(order_free_corner_error(kSquare, q), 0.0) << "order " << order;
    EXPECT_EQ(order_free_corner_error(q, kSquare), 0.0) << "order " << order;
  }
}

TEST(OrderFreeCornerError, IsTheWorstCornerOfTheBestPairing) {
  Quad moved;
  copy(kSquare, moved);
  moved[2] = {7, 8};  // 5 px from (4, 4)
  moved[0] = {1, 0};  // 1 px from (0, 0)
  for (int order = 0; order < 8; ++order) {
    Quad q;
    reorder(moved, order, q);
    EXPECT_NEAR(order_free_corner_error(kSquare, q), 5.0, 1e-6) << "order " << order;
  }
}

TEST(OrderFreeCornerError, CrossedOrderIsNotAcceptedAsTheSameOutline) {
  // Corners listed across the diagonals pair up with no cyclic order.
  const Quad crossed = {{0, 0}, {4, 4}, {4, 0}, {0, 4}};
  EXPECT_NEAR(order_free_corner_error(kSquare, crossed), 4.0, 1e-6);
}

TEST(OrderFreeCornerError, NanCornersAreInfinitelyFar) {
  Quad q;
  copy(kSquare, q);
  q[1].x = std::nanf("");
  EXPECT_TRUE(std::isinf(order_free_corner_error(kSquare, q)));
}

TEST(QuadIou, KnownOverlapsInEveryOrder) {
  const Quad shifted = {{2, 0}, {6, 0}, {6, 4}, {2, 4}};  // half of the square: 8 / 24
  const Quad inner = {{1, 1}, {3, 1}, {3, 3}, {1, 3}};    // 4 / 16
  const Quad apart = {{10, 10}, {12, 10}, {12, 12}, {10, 12}};
  for (int order = 0; order < 8; ++order) {
    Quad a, b, c, d;
    reorder(kSquare, order, a);
    reorder(shifted, 7 - order, b);
    reorder(inner, order, c);
    reorder(apart, order, d);
    EXPECT_NEAR(quad_iou(a, kSquare), 1.0, 1e-12) << "order " << order;
    EXPECT_NEAR(quad_iou(a, b), 1.0 / 3.0, 1e-12) << "order " << order;
    EXPECT_NEAR(quad_iou(c, a), 0.25, 1e-12) << "order " << order;
    EXPECT_EQ(quad_iou(a, d), 0.0) << "order " << order;
  }
}

TEST(QuadIou, NonConvexInEveryOrder) {
  // The dart (area 6) lies inside the square (area 16).
  EXPECT_NEAR(std::abs(signed_area(kDart)), 6.0, 1e-12);
  const Quad left_half = {{0, 0}, {2, 0}, {2, 4}, {0, 4}};
  const double reference = raster_iou(kDart, left_half, 0, 4, 800);
  for (int order = 0; order < 8; ++order) {
    Quad d;
    reorder(kDart, order, d);
    EXPECT_TRUE(is_simple_quad(d)) << "order " << order;
    EXPECT_NEAR(quad_iou(d, kSquare), 6.0 / 16.0, 1e-12) << "order " << order;
    EXPECT_NEAR(quad_iou(kDart, d), 1.0, 1e-12) << "order " << order;
    EXPECT_NEAR(quad_iou(d, left_half), reference, 0.005) << "order " << order;
  }
  // Two darts pointing at each other, against the raster.
  const Quad mirrored = {{4, 0}, {0, 2}, {4, 4}, {3, 2}};
  EXPECT_NEAR(quad_iou(kDart, mirrored), raster_iou(kDart, mirrored, 0, 4, 800), 0.005);
}

TEST(QuadIou, MatchesARasterOnRandomQuadrilaterals) {
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> coord(0.f, 20.f);
  int compared = 0, non_convex = 0;
  for (int trial = 0; trial < 400 && compared < 60; ++trial) {
    Quad a, b;
    for (int i = 0; i < 4; ++i) a[i] = {coord(rng), coord(rng)}, b[i] = {coord(rng), coord(rng)};
    if (!is_simple_quad(a) || !is_simple_quad(b)) continue;
    if (std::abs(signed_area(a)) < 20 || std::abs(signed_area(b)) < 20) continue;
    auto convex = [](const Quad& q) {
      int sign = 0;
      for (int i = 0; i < 4; ++i) {
        const Point2f &p = q[i], &c = q[(i + 1) % 4], &n = q[(i + 2) % 4];
        const double z =
            (double{c.x} - p.x) * (double{n.y} - c.y) - (double{c.y} - p.y) * (double{n.x} - c.x);
        const int s = z > 0 ? 1 : -1;
        if (sign != 0 && s != sign) return false;
        sign = s;
      }
      return true;
    };
    non_convex += !convex(a) || !convex(b);
    EXPECT_NEAR(quad_iou(a, b), raster_iou(a, b, 0, 20, 600), 0.01) << "trial " << trial;
    ++compared;
  }
  EXPECT_EQ(compared, 60);
  EXPECT_GT(non_convex, 5);  // the sample does exercise non-convex shapes
}

TEST(QuadIou, DegenerateQuadrilateralsOverlapNothing) {
  const Quad bow_tie = {{0, 0}, {4, 4}, {4, 0}, {0, 4}};
  const Quad collinear = {{0, 0}, {2, 0}, {4, 0}, {0, 4}};  // a triangle with a corner on a side
  const Quad repeated = {{0, 0}, {0, 0}, {4, 4}, {0, 4}};
  const Quad flat = {{0, 0}, {1, 1}, {2, 2}, {3, 3}};
  const Quad point = {{1, 1}, {1, 1}, {1, 1}, {1, 1}};
  Quad nan;
  copy(kSquare, nan);
  nan[2].y = std::nanf("");
  const Quad* degenerate[] = {&bow_tie, &collinear, &repeated, &flat, &point, &nan};
  for (const Quad* q : degenerate) {
    EXPECT_FALSE(is_simple_quad(*q));
    EXPECT_EQ(quad_iou(*q, kSquare), 0.0);
    EXPECT_EQ(quad_iou(kSquare, *q), 0.0);
    EXPECT_EQ(quad_iou(*q, *q), 0.0);
  }
  EXPECT_TRUE(is_simple_quad(kSquare));
}

TEST(LongestSide, OfARectangle) {
  const Quad r = {{0, 0}, {30, 0}, {30, 10}, {0, 10}};
  EXPECT_NEAR(longest_side(r), 30.0, 1e-12);
}

}  // namespace
}  // namespace kg
