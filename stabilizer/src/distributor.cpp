#include "overstep/stabilizer/distributor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace overstep::stabilizer {
namespace {

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

Eigen::Vector2d closestOnSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                 const Eigen::Vector2d& p) {
  const Eigen::Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return a + t * ab;
}

/// A sole rectangle (shrunk) as an oriented box on the ground plane.
struct Box2 {
  Eigen::Vector2d origin;
  Eigen::Matrix2d R;  ///< columns: sole x and y axes in the world
  double x0, x1, y0, y1;
  Eigen::Vector2d project(const Eigen::Vector2d& p) const {
    Eigen::Vector2d l = R.transpose() * (p - origin);
    l.x() = std::clamp(l.x(), x0, x1);
    l.y() = std::clamp(l.y(), y0, y1);
    return origin + R * l;
  }
};

Box2 makeBox(const Sole& s, const Eigen::Isometry3d& X, double margin) {
  Box2 b;
  b.origin = X.translation().head<2>();
  const double yaw = std::atan2(X.linear()(1, 0), X.linear()(0, 0));
  b.R = Eigen::Rotation2Dd(yaw).toRotationMatrix();
  // A margin larger than half the sole collapses that side to the centre line.
  const double cx = 0.5 * (s.x_min + s.x_max), cy = 0.5 * (s.y_min + s.y_max);
  b.x0 = std::min(s.x_min + margin, cx);
  b.x1 = std::max(s.x_max - margin, cx);
  b.y0 = std::min(s.y_min + margin, cy);
  b.y1 = std::max(s.y_max - margin, cy);
  return b;
}

struct Split {
  Eigen::Vector2d a, b;  ///< right and left CoP (world)
  double residual;       ///< |alpha a + (1 - alpha) b - p|
};

/// Dykstra's alternating projections between {alpha a + (1 - alpha) b = p} and the product of the
/// two sole boxes, started from the sole origins: converges to the pair of CoPs closest to the
/// ankles (least ankle torque) that realises p with share alpha, when one exists.
Split splitFor(double alpha, const Eigen::Vector2d& p, const Box2& R, const Box2& L) {
  Eigen::Vector4d x;
  x << R.origin, L.origin;
  Eigen::Vector4d inc_aff = Eigen::Vector4d::Zero(), inc_box = Eigen::Vector4d::Zero();
  const double beta = 1.0 - alpha;
  const double den = alpha * alpha + beta * beta;
  for (int it = 0; it < 200; ++it) {
    Eigen::Vector4d y = x + inc_aff;
    const Eigen::Vector2d r = p - (alpha * y.head<2>() + beta * y.tail<2>());
    y.head<2>() += (alpha / den) * r;
    y.tail<2>() += (beta / den) * r;
    inc_aff = x + inc_aff - y;
    Eigen::Vector4d z = y + inc_box;
    Eigen::Vector4d xn;
    xn << R.project(z.head<2>()), L.project(z.tail<2>());
    inc_box = y + inc_box - xn;
    const double change = (xn - x).squaredNorm();
    x = xn;
    if (change < 1e-24) break;
  }
  const Eigen::Vector2d a = x.head<2>(), b = x.tail<2>();
  return {a, b, (alpha * a + beta * b - p).norm()};
}

}  // namespace

bool Polygon::contains(const Eigen::Vector2d& p, double tol) const {
  if (n == 0) return false;
  if (n < 3) return (closest(p) - p).norm() <= tol;
  for (int i = 0; i < n; ++i)
    if (cross(v[static_cast<std::size_t>(i)], v[static_cast<std::size_t>((i + 1) % n)], p) < -tol)
      return false;
  return true;
}

Eigen::Vector2d Polygon::closest(const Eigen::Vector2d& p) const {
  if (n == 0) return p;
  if (n == 1) return v[0];
  if (n >= 3 && contains(p, 0.0)) return p;
  Eigen::Vector2d best = v[0];
  double best_d = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d c = closestOnSegment(v[static_cast<std::size_t>(i)],
                                               v[static_cast<std::size_t>((i + 1) % n)], p);
    const double d = (c - p).squaredNorm();
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

std::array<Eigen::Vector2d, 4> soleCorners(const Sole& s, const Eigen::Isometry3d& X_WS,
                                           double margin) {
  const Box2 b = makeBox(s, X_WS, margin);
  return {
      b.origin + b.R * Eigen::Vector2d(b.x0, b.y0), b.origin + b.R * Eigen::Vector2d(b.x1, b.y0),
      b.origin + b.R * Eigen::Vector2d(b.x1, b.y1), b.origin + b.R * Eigen::Vector2d(b.x0, b.y1)};
}

Polygon convexHull(const Eigen::Vector2d* pts, int n) {
  constexpr int kIn = 32;
  std::array<Eigen::Vector2d, kIn> s;
  n = std::clamp(n, 0, kIn);
  for (int i = 0; i < n; ++i) s[static_cast<std::size_t>(i)] = pts[i];
  // Insertion sort by (x, y): n <= 32 (std::sort here trips GCC 12's -Warray-bounds at -O3).
  for (int i = 1; i < n; ++i) {
    const Eigen::Vector2d key = s[static_cast<std::size_t>(i)];
    int j = i - 1;
    for (; j >= 0; --j) {
      const Eigen::Vector2d& c = s[static_cast<std::size_t>(j)];
      if (!(key.x() < c.x() || (key.x() == c.x() && key.y() < c.y()))) break;
      s[static_cast<std::size_t>(j + 1)] = c;
    }
    s[static_cast<std::size_t>(j + 1)] = key;
  }
  Polygon h;
  if (n < 3) {
    for (int i = 0; i < n; ++i)
      h.v[static_cast<std::size_t>(h.n++)] = s[static_cast<std::size_t>(i)];
    return h;
  }
  std::array<Eigen::Vector2d, 2 * kIn + 1> out;  // Andrew's monotone chain
  int k = 0;
  auto push = [&](int i, int floor) {
    const Eigen::Vector2d& q = s[static_cast<std::size_t>(i)];
    while (k >= floor && cross(out[static_cast<std::size_t>(k - 2)],
                               out[static_cast<std::size_t>(k - 1)], q) <= 1e-15)
      --k;
    out[static_cast<std::size_t>(k++)] = q;
  };
  for (int i = 0; i < n; ++i) push(i, 2);
  const int lower = k + 1;
  for (int i = n - 2; i >= 0; --i) push(i, lower);
  h.n = std::min(k - 1, Polygon::kMax);
  for (int i = 0; i < h.n; ++i) h.v[static_cast<std::size_t>(i)] = out[static_cast<std::size_t>(i)];
  return h;
}

Distribution distributeWrench(const Eigen::Vector2d& zmp, const Eigen::Vector3d& force, double mz,
                              const std::array<bool, 2>& contact,
                              const std::array<Eigen::Isometry3d, 2>& sole_pose,
                              const std::array<Sole, 2>& sole, double margin, double min_force,
                              double alpha_pref) {
  Distribution d;
  const Box2 box[2] = {makeBox(sole[0], sole_pose[0], margin),
                       makeBox(sole[1], sole_pose[1], margin)};
  Eigen::Vector2d p = zmp;
  if (contact[0] && contact[1]) {
    const double fz = std::max(force.z(), 1e-9);
    const double lo = std::clamp(min_force / fz, 0.0, 0.5);
    // Realisable ZMPs: {a r + (1 - a) l : r in R, l in L, a in [lo, 1 - lo]} = the convex hull of
    // the two end slices' Minkowski sums (the set {(a, p)} is the convex hull of {1} x R and
    // {0} x L), i.e. of 32 points a r_i + (1 - a) l_j.
    const auto cr = soleCorners(sole[0], sole_pose[0], margin);
    const auto cl = soleCorners(sole[1], sole_pose[1], margin);
    std::array<Eigen::Vector2d, 32> pts;
    std::array<Eigen::Vector3i, 32> tag;  // (end slice, right corner, left corner)
    int k = 0;
    for (int e = 0; e < 2; ++e) {
      const double a = e == 0 ? lo : 1.0 - lo;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          pts[static_cast<std::size_t>(k)] =
              a * cr[static_cast<std::size_t>(i)] + (1.0 - a) * cl[static_cast<std::size_t>(j)];
          tag[static_cast<std::size_t>(k++)] = Eigen::Vector3i(e, i, j);
        }
    }
    const Polygon reach = convexHull(pts.data(), 32);
    if (!reach.contains(p, 1e-12)) {
      p = reach.closest(p);
      d.clamped = true;
    }
    // Shares that realise p: p is in a R + (1 - a) L iff for every edge normal n of either sole
    // n.p <= a h_R(n) + (1 - a) h_L(n) (support functions; the Minkowski sum's edge normals are
    // those of its terms), a bound on a per normal: the feasible interval in closed form.
    double amin = lo, amax = 1.0 - lo;
    for (const auto* poly : {&cr, &cl}) {
      for (std::size_t e = 0; e < 4; ++e) {
        const Eigen::Vector2d edge = (*poly)[(e + 1) % 4] - (*poly)[e];
        const Eigen::Vector2d n(edge.y(), -edge.x());  // outward for a CCW polygon
        double hr = -std::numeric_limits<double>::infinity(), hl = hr;
        for (std::size_t c = 0; c < 4; ++c) {
          hr = std::max(hr, n.dot(cr[c]));
          hl = std::max(hl, n.dot(cl[c]));
        }
        const double slope = hr - hl, rhs = n.dot(p) - hl;
        if (slope > 1e-15)
          amin = std::max(amin, rhs / slope);
        else if (slope < -1e-15)
          amax = std::min(amax, rhs / slope);
      }
    }
    const double a0 = std::clamp(std::isfinite(alpha_pref) ? alpha_pref : 0.5, lo, 1.0 - lo);
    // The preferred share when it is feasible; otherwise the nearest feasible one, moved 2 % of
    // the interval inside so that the projections below converge quickly.
    const double inset = 0.02 * std::max(amax - amin, 0.0);
    const double alpha0 = a0 < amin ? amin + inset : (a0 > amax ? amax - inset : a0);
    constexpr double kTol = 1e-10;
    Split s = splitFor(std::clamp(alpha0, lo, 1.0 - lo), p, box[0], box[1]);
    double alpha = std::clamp(alpha0, lo, 1.0 - lo);
    if (s.residual > kTol) {
      // On (or within round-off of) the realisable boundary, where alternating projections
      // converge slowly: decompose exactly with the barycentric coordinates of p in a fan
      // triangle of the realisable polygon (Caratheodory), lifted to (alpha, CoP_R, CoP_L).
      auto vertexTag = [&](const Eigen::Vector2d& v) {
        int best = 0;
        double bd = std::numeric_limits<double>::infinity();
        for (int q = 0; q < 32; ++q) {
          const double dd = (pts[static_cast<std::size_t>(q)] - v).squaredNorm();
          if (dd < bd) bd = dd, best = q;
        }
        return tag[static_cast<std::size_t>(best)];
      };
      for (int t = 1; t + 1 < reach.n; ++t) {
        const Eigen::Vector2d& A = reach.v[0];
        const Eigen::Vector2d& B = reach.v[static_cast<std::size_t>(t)];
        const Eigen::Vector2d& C = reach.v[static_cast<std::size_t>(t + 1)];
        Eigen::Matrix2d M;
        M << B - A, C - A;
        if (std::abs(M.determinant()) < 1e-18) continue;
        const Eigen::Vector2d bc = M.inverse() * (p - A);
        const double w[3] = {1.0 - bc.x() - bc.y(), bc.x(), bc.y()};
        if (w[0] < -1e-9 || w[1] < -1e-9 || w[2] < -1e-9) continue;
        const Eigen::Vector3i tg[3] = {vertexTag(A), vertexTag(B), vertexTag(C)};
        double al = 0.0;
        Eigen::Vector2d sr = Eigen::Vector2d::Zero(), sl = Eigen::Vector2d::Zero();
        for (int q = 0; q < 3; ++q) {
          const double a = tg[q](0) == 0 ? lo : 1.0 - lo;
          al += w[q] * a;
          sr += w[q] * a * cr[static_cast<std::size_t>(tg[q](1))];
          sl += w[q] * (1.0 - a) * cl[static_cast<std::size_t>(tg[q](2))];
        }
        alpha = al;
        // A foot without load keeps its CoP at its ankle (its wrench is zero anyway).
        const Eigen::Vector2d pr = al > 1e-12 ? Eigen::Vector2d(sr / al) : box[0].origin;
        const Eigen::Vector2d pl =
            al < 1.0 - 1e-12 ? Eigen::Vector2d(sl / (1.0 - al)) : box[1].origin;
        s = {pr, pl, (sr + sl - p).norm()};
        break;
      }
    }
    d.alpha = alpha;
    d.cop_world = {box[0].project(s.a), box[1].project(s.b)};
  } else {
    const int f = contact[0] ? 0 : (contact[1] ? 1 : -1);
    if (f < 0) return d;  // no support: zero wrenches
    const Polygon poly = [&] {
      Polygon q;
      const auto c = soleCorners(sole[static_cast<std::size_t>(f)],
                                 sole_pose[static_cast<std::size_t>(f)], margin);
      for (const auto& v : c) q.v[static_cast<std::size_t>(q.n++)] = v;
      return q;
    }();
    if (!poly.contains(p, 1e-12)) {
      p = poly.closest(p);
      d.clamped = true;
    }
    d.alpha = f == 0 ? 1.0 : 0.0;
    d.cop_world[static_cast<std::size_t>(f)] = p;
    d.cop_world[static_cast<std::size_t>(1 - f)] =
        sole_pose[static_cast<std::size_t>(1 - f)].translation().head<2>();
  }
  const double share[2] = {d.alpha, 1.0 - d.alpha};
  d.zmp.setZero();
  for (int f = 0; f < 2; ++f) {
    const auto fi = static_cast<std::size_t>(f);
    d.zmp += share[f] * d.cop_world[fi];
    const Eigen::Isometry3d& X = sole_pose[fi];
    const Eigen::Vector3d P(d.cop_world[fi].x(), d.cop_world[fi].y(), X.translation().z());
    const core::Wrench w_P(share[f] * force, Eigen::Vector3d(0.0, 0.0, share[f] * mz), P,
                           core::Axes::kWorld);
    const core::Wrench w_W = w_P.about(X.translation());
    d.wrench[fi] =
        core::Wrench(X.linear().transpose() * w_W.force, X.linear().transpose() * w_W.moment,
                     Eigen::Vector3d::Zero(), core::Axes::kSole);
  }
  d.error = (d.zmp - zmp).norm();
  return d;
}

}  // namespace overstep::stabilizer
