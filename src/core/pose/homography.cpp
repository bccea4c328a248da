// Homography estimation: normalised DLT, Levenberg-Marquardt refinement and
// the pose plausibility test. Fixed-size Eigen types only: nothing here
// allocates, so these run inside the detector's per-frame path.
#include "core/pose/homography.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace kg {
namespace {

using Mat3 = Eigen::Matrix3d;
using Mat8 = Eigen::Matrix<double, 8, 8>;
using Vec8 = Eigen::Matrix<double, 8, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9>;
using Vec9 = Eigen::Matrix<double, 9, 1>;

// Twice the area of a triangle of normalised points (mean distance to the
// centroid sqrt(2)) below this counts as collinear: a vertex within about
// 0.35 % of the spread from the line through the other two.
constexpr double kCollinearTolerance = 1e-2;
// Smallest over largest eigenvalue of the 2x2 scatter of normalised points
// below this: the whole set lies on a line (n > 4).
constexpr double kLineSpreadTolerance = 1e-6;
// Second smallest over largest eigenvalue of the normalised A^T A below
// this: the DLT null space is not one-dimensional (n > 4).
constexpr double kRankTolerance = 1e-10;
// Smallest over largest LDLT pivot of the h33 = 1 normal equations below
// this: not trusted (an ill-conditioned or degenerate set, or h33 near 0);
// the eigen solver decides instead (n > 4).
constexpr double kLsqPivotTolerance = 1e-8;
// |h33| below this times the largest |h_ij|: h33 cannot be scaled to 1.
constexpr double kTinyH33 = 1e-12;

// Hartley normalisation x' = s (x - c): centroid at the origin, mean
// distance to it sqrt(2).
struct Normaliser {
  double cx = 0.0;
  double cy = 0.0;
  double s = 1.0;
  double x(const Point2f& p) const { return s * (p.x - cx); }
  double y(const Point2f& p) const { return s * (p.y - cy); }
  Mat3 matrix() const {
    Mat3 t;
    t << s, 0.0, -s * cx, 0.0, s, -s * cy, 0.0, 0.0, 1.0;
    return t;
  }
  Mat3 inverse() const {
    Mat3 t;
    t << 1.0 / s, 0.0, cx, 0.0, 1.0 / s, cy, 0.0, 0.0, 1.0;
    return t;
  }
};

// False when the points are not finite or all coincide.
bool make_normaliser(const Point2f* p, int n, Normaliser& out) {
  double cx = 0.0;
  double cy = 0.0;
  for (int i = 0; i < n; ++i) {
    cx += p[i].x;
    cy += p[i].y;
  }
  cx /= n;
  cy /= n;
  double mean = 0.0;
  for (int i = 0; i < n; ++i) mean += std::hypot(p[i].x - cx, p[i].y - cy);
  mean /= n;
  if (!std::isfinite(cx) || !std::isfinite(cy) || !std::isfinite(mean)) return false;
  // Relative to the coordinates' magnitude: float points closer than this
  // are the same point up to rounding.
  if (!(mean > 1e-7 * (1.0 + std::abs(cx) + std::abs(cy)))) return false;
  out.cx = cx;
  out.cy = cy;
  out.s = std::sqrt(2.0) / mean;
  return true;
}

// Any three of the four points collinear (or two coincident).
bool has_collinear_triple(const Point2f* p, const Normaliser& nm) {
  double x[4];
  double y[4];
  for (int i = 0; i < 4; ++i) {
    x[i] = nm.x(p[i]);
    y[i] = nm.y(p[i]);
  }
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      for (int k = j + 1; k < 4; ++k) {
        const double cross = (x[j] - x[i]) * (y[k] - y[i]) - (y[j] - y[i]) * (x[k] - x[i]);
        if (std::abs(cross) < kCollinearTolerance) return true;
      }
    }
  }
  return false;
}

// All points on one line: the scatter matrix has a (near) zero eigenvalue.
bool all_on_a_line(const Point2f* p, int n, const Normaliser& nm) {
  double sxx = 0.0;
  double sxy = 0.0;
  double syy = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = nm.x(p[i]);
    const double y = nm.y(p[i]);
    sxx += x * x;
    sxy += x * y;
    syy += y * y;
  }
  const double half_trace = 0.5 * (sxx + syy);
  const double root = std::hypot(0.5 * (sxx - syy), sxy);
  const double largest = half_trace + root;
  const double smallest = half_trace - root;
  return !(smallest > kLineSpreadTolerance * largest);
}

// The two DLT rows of one normalised correspondence (x, y) -> (u, v).
void dlt_rows(double x, double y, double u, double v, Vec9& r1, Vec9& r2) {
  r1 << 0.0, 0.0, 0.0, -x, -y, -1.0, v * x, v * y, v;
  r2 << x, y, 1.0, 0.0, 0.0, 0.0, -u * x, -u * y, -u;
}

// Scales so that h33 == 1 when it is not tiny, else to unit norm. False
// when not finite.
bool normalise_scale(Mat3& h) {
  const double largest = h.cwiseAbs().maxCoeff();
  if (!std::isfinite(largest) || !(largest > 0.0)) return false;
  if (std::abs(h(2, 2)) > kTinyH33 * largest) {
    h /= h(2, 2);
  } else {
    h /= h.norm();
  }
  return h.allFinite();
}

Mat3 to_matrix(const Homography& h) {
  Mat3 m;
  m << h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8];
  return m;
}

void from_matrix(const Mat3& m, Homography& h) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) h[3 * r + c] = m(r, c);
  }
}

// Sum of squared residuals of the 8-parameter homography (h33 = 1) in
// normalised coordinates; infinite when a point maps to infinity.
double lm_cost(const Vec8& p, const Point2f* model, const Point2f* scene, int n,
               const Normaliser& nm, const Normaliser& ns) {
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = nm.x(model[i]);
    const double y = nm.y(model[i]);
    const double w = p[6] * x + p[7] * y + 1.0;
    if (w == 0.0) return HUGE_VAL;
    const double ru = (p[0] * x + p[1] * y + p[2]) / w - ns.x(scene[i]);
    const double rv = (p[3] * x + p[4] * y + p[5]) / w - ns.y(scene[i]);
    sum += ru * ru + rv * rv;
  }
  return std::isfinite(sum) ? sum : HUGE_VAL;
}

bool fit(const Point2f* model, const Point2f* scene, int n, bool fast, Homography& h) {
  if (model == nullptr || scene == nullptr || n < 4) return false;
  Normaliser nm;
  Normaliser ns;
  if (!make_normaliser(model, n, nm) || !make_normaliser(scene, n, ns)) return false;

  Vec9 hn;
  bool solved = false;
  Vec9 r1;
  Vec9 r2;
  if (n == 4) {
    if (has_collinear_triple(model, nm) || has_collinear_triple(scene, ns)) return false;
    // Exactly determined: fix h33 = 1 and solve the 8x8 system.
    Mat8 a;
    Vec8 b;
    for (int i = 0; i < 4; ++i) {
      dlt_rows(nm.x(model[i]), nm.y(model[i]), ns.x(scene[i]), ns.y(scene[i]), r1, r2);
      a.row(2 * i) = r1.head<8>().transpose();
      a.row(2 * i + 1) = r2.head<8>().transpose();
      b[2 * i] = -r1[8];
      b[2 * i + 1] = -r2[8];
    }
    const Eigen::FullPivLU<Mat8> lu(a);
    // Singular only when the normalised h33 is 0 (the model centroid maps to
    // infinity); the null-space solution below still handles that case.
    if (lu.isInvertible()) {
      hn.head<8>() = lu.solve(b);
      hn[8] = 1.0;
      solved = hn.allFinite();
    }
  } else if (all_on_a_line(model, n, nm) || all_on_a_line(scene, n, ns)) {
    return false;
  }

  if (!solved && fast) {
    // n > 4, well conditioned: least squares with h33 = 1, the 8x8 normal
    // equations by LDLT, about a tenth of the eigen solver's cost.
    Mat8 normal = Mat8::Zero();
    Vec8 rhs = Vec8::Zero();
    for (int i = 0; i < n; ++i) {
      dlt_rows(nm.x(model[i]), nm.y(model[i]), ns.x(scene[i]), ns.y(scene[i]), r1, r2);
      normal.selfadjointView<Eigen::Lower>().rankUpdate(r1.head<8>());
      normal.selfadjointView<Eigen::Lower>().rankUpdate(r2.head<8>());
      rhs -= r1[8] * r1.head<8>() + r2[8] * r2.head<8>();
    }
    const Eigen::LDLT<Mat8, Eigen::Lower> ldlt(normal);
    const Vec8 pivots = ldlt.vectorD();
    if (ldlt.info() == Eigen::Success &&
        pivots.minCoeff() > kLsqPivotTolerance * pivots.maxCoeff()) {
      hn.head<8>() = ldlt.solve(rhs);
      hn[8] = 1.0;
      solved = hn.allFinite();
    }
  }
  if (!solved) {
    // Least squares: the eigenvector of A^T A with the smallest eigenvalue,
    // A^T A accumulated row by row so that no n x 9 matrix is needed.
    Mat9 ata = Mat9::Zero();
    for (int i = 0; i < n; ++i) {
      dlt_rows(nm.x(model[i]), nm.y(model[i]), ns.x(scene[i]), ns.y(scene[i]), r1, r2);
      ata.selfadjointView<Eigen::Lower>().rankUpdate(r1);
      ata.selfadjointView<Eigen::Lower>().rankUpdate(r2);
    }
    // The solver reads only the lower triangle, which is what rankUpdate fills.
    const Eigen::SelfAdjointEigenSolver<Mat9> eig(ata);
    if (eig.info() != Eigen::Success) return false;
    const Vec9& ev = eig.eigenvalues();  // ascending
    if (!(ev[1] > kRankTolerance * ev[8])) return false;
    hn = eig.eigenvectors().col(0);
  }

  Mat3 hm;
  hm << hn[0], hn[1], hn[2], hn[3], hn[4], hn[5], hn[6], hn[7], hn[8];
  Mat3 full = ns.inverse() * hm * nm.matrix();
  if (!normalise_scale(full)) return false;
  from_matrix(full, h);
  return true;
}

}  // namespace

bool fit_homography(const Point2f* model, const Point2f* scene, int n, Homography& h) {
  return fit(model, scene, n, false, h);
}

bool fit_homography_hypothesis(const Point2f* model, const Point2f* scene, int n, Homography& h) {
  return fit(model, scene, n, true, h);
}

double rms_reprojection_error(const Point2f* model, const Point2f* scene, int n,
                              const Homography& h) {
  if (n <= 0) return 0.0;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = model[i].x;
    const double y = model[i].y;
    const double w = h[6] * x + h[7] * y + h[8];
    const double du = (h[0] * x + h[1] * y + h[2]) / w - scene[i].x;
    const double dv = (h[3] * x + h[4] * y + h[5]) / w - scene[i].y;
    sum += du * du + dv * dv;
  }
  const double rms = std::sqrt(sum / n);
  return std::isfinite(rms) ? rms : HUGE_VAL;
}

double refine_homography(const Point2f* model, const Point2f* scene, int n, Homography& h,
                         int max_iterations) {
  const double initial_rms = rms_reprojection_error(model, scene, n, h);
  if (n < 4 || !std::isfinite(initial_rms)) return initial_rms;
  Normaliser nm;
  Normaliser ns;
  if (!make_normaliser(model, n, nm) || !make_normaliser(scene, n, ns)) return initial_rms;

  // Optimise in normalised coordinates for a well-conditioned J^T J; the
  // residuals there are the pixel residuals times ns.s, so the minimiser is
  // the same.
  Mat3 hm = ns.matrix() * to_matrix(h) * nm.inverse();
  if (!(std::abs(hm(2, 2)) > kTinyH33 * hm.cwiseAbs().maxCoeff())) return initial_rms;
  hm /= hm(2, 2);
  Vec8 p;
  p << hm(0, 0), hm(0, 1), hm(0, 2), hm(1, 0), hm(1, 1), hm(1, 2), hm(2, 0), hm(2, 1);

  double cost = lm_cost(p, model, scene, n, nm, ns);
  if (!std::isfinite(cost)) return initial_rms;
  double lambda = 1e-3;
  bool moved = false;
  Eigen::Matrix<double, 8, 1> ju;
  Eigen::Matrix<double, 8, 1> jv;
  for (int iter = 0; iter < max_iterations; ++iter) {
    Mat8 jtj = Mat8::Zero();
    Vec8 jtr = Vec8::Zero();
    for (int i = 0; i < n; ++i) {
      const double x = nm.x(model[i]);
      const double y = nm.y(model[i]);
      const double iw = 1.0 / (p[6] * x + p[7] * y + 1.0);
      const double pu = (p[0] * x + p[1] * y + p[2]) * iw;
      const double pv = (p[3] * x + p[4] * y + p[5]) * iw;
      ju << x * iw, y * iw, iw, 0.0, 0.0, 0.0, -pu * x * iw, -pu * y * iw;
      jv << 0.0, 0.0, 0.0, x * iw, y * iw, iw, -pv * x * iw, -pv * y * iw;
      jtj.selfadjointView<Eigen::Lower>().rankUpdate(ju);
      jtj.selfadjointView<Eigen::Lower>().rankUpdate(jv);
      jtr += ju * (pu - ns.x(scene[i])) + jv * (pv - ns.y(scene[i]));
    }
    for (int r = 0; r < 8; ++r) {
      for (int c = r + 1; c < 8; ++c) jtj(r, c) = jtj(c, r);
    }
    if (!jtj.allFinite() || !jtr.allFinite()) break;
    if (jtr.cwiseAbs().maxCoeff() <= 1e-15 * (1.0 + cost)) break;  // at a stationary point

    // Marquardt damping on the diagonal: larger lambda, shorter gradient-like
    // step; grow it until the cost drops.
    bool improved = false;
    Vec8 step = Vec8::Zero();
    double new_cost = cost;
    for (int attempt = 0; attempt < 12 && !improved; ++attempt) {
      Mat8 damped = jtj;
      damped.diagonal() += lambda * (jtj.diagonal().array() + 1e-12).matrix();
      step = damped.ldlt().solve(-jtr);
      if (step.allFinite()) {
        new_cost = lm_cost(p + step, model, scene, n, nm, ns);
        improved = new_cost < cost;
      }
      if (improved) {
        lambda = std::max(lambda * 0.1, 1e-12);
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
    p += step;
    moved = true;
    const double gain = cost - new_cost;
    cost = new_cost;
    if (gain <= 1e-12 * cost || step.norm() <= 1e-12 * (1.0 + p.norm())) break;
  }

  // Without an accepted step, skip the round trip through the normalisation
  // so the input comes back bit for bit.
  if (!moved) return initial_rms;
  hm << p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], 1.0;
  Mat3 full = ns.inverse() * hm * nm.matrix();
  if (!normalise_scale(full)) return initial_rms;
  Homography refined;
  from_matrix(full, refined);
  const double refined_rms = rms_reprojection_error(model, scene, n, refined);
  // The pixel-space error decides: never hand back a worse homography.
  if (!(refined_rms < initial_rms)) return initial_rms;
  h = refined;
  return refined_rms;
}

double smallest_area_scale(const Params& params, float model_width, float model_height) {
  const double symmetric = 1.0 / params.ransac.max_scale_change;
  const double long_edge = std::max(model_width, model_height);
  if (!(params.views.min_size > 0.f) || !(long_edge > 0.0)) return symmetric;
  const double linear = params.views.min_size / (1.5 * long_edge);
  return std::min(symmetric, linear * linear);
}

bool is_plausible_pose(const Homography& h, float model_width, float model_height,
                       const RansacParams& params) {
  return is_plausible_pose(h, model_width, model_height, params, 0.0);
}

bool is_plausible_pose(const Homography& h, float model_width, float model_height,
                       const RansacParams& params, double min_area) {
  const double mw = model_width;
  const double mh = model_height;
  if (!(mw > 0.0) || !(mh > 0.0)) return false;
  for (double v : h) {
    if (!std::isfinite(v)) return false;
  }
  double largest = 0.0;
  for (double v : h) largest = std::max(largest, std::abs(v));
  if (!(std::abs(h[8]) > kTinyH33 * largest)) return false;  // origin at infinity
  double g[9];
  for (int i = 0; i < 9; ++i) g[i] = h[i] / h[8];

  // Perspective: the change of w along each model side, relative to the
  // model's larger side.
  const double size = std::max(mw, mh);
  if (!(std::abs(g[6]) * mw <= params.max_perspective * size)) return false;
  if (!(std::abs(g[7]) * mh <= params.max_perspective * size)) return false;

  // Corners in model order (0,0), (w,0), (w,h), (0,h); w is affine, so
  // positive at the corners means positive over the whole rectangle.
  const double cx[4] = {0.0, mw, mw, 0.0};
  const double cy[4] = {0.0, 0.0, mh, mh};
  double qx[4];
  double qy[4];
  for (int i = 0; i < 4; ++i) {
    const double w = g[6] * cx[i] + g[7] * cy[i] + g[8];
    if (!(w > 0.0)) return false;
    qx[i] = (g[0] * cx[i] + g[1] * cy[i] + g[2]) / w;
    qy[i] = (g[3] * cx[i] + g[4] * cy[i] + g[5]) / w;
    if (!std::isfinite(qx[i]) || !std::isfinite(qy[i])) return false;
  }

  // Convex with the model's orientation: every turn has the sign of the
  // model rectangle's turns (positive cross products). Four same-signed
  // turns of a quadrilateral imply it is simple and convex.
  double area2 = 0.0;
  constexpr double kMinSide = 4.0;
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    const int k = (i + 2) % 4;
    const double ex = qx[j] - qx[i];
    const double ey = qy[j] - qy[i];
    if (std::hypot(ex, ey) < kMinSide) return false;
    const double turn = ex * (qy[k] - qy[j]) - ey * (qx[k] - qx[j]);
    if (!(turn > 0.0)) return false;
    area2 += qx[i] * qy[j] - qx[j] * qy[i];
  }

  const double ratio = 0.5 * area2 / (mw * mh);
  const double max_scale = params.max_scale_change;
  const double lowest = min_area > 0.0 ? std::min(1.0 / max_scale, min_area) : 1.0 / max_scale;
  return ratio >= lowest && ratio <= max_scale;
}

}  // namespace kg
