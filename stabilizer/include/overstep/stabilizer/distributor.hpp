#pragma once
/// \file
/// Support polygon and wrench distribution between the feet (Kajita 2010's ZMP distributor, made
/// exact): the desired ZMP is split into a normal-force ratio and one CoP per foot such that the
/// force-weighted mean of the CoPs is the desired ZMP and each CoP lies in its (shrunk) sole.
/// Fixed-size, allocation-free, no exceptions.

#include <Eigen/Geometry>
#include <array>

#include "overstep/core/wrench.hpp"
#include "overstep/stabilizer/params.hpp"

namespace overstep::stabilizer {

/// Convex polygon with at most 16 vertices, counter-clockwise, on the ground plane.
struct Polygon {
  static constexpr int kMax = 16;
  std::array<Eigen::Vector2d, kMax> v{};
  int n = 0;
  Polygon() { v.fill(Eigen::Vector2d::Zero()); }
  bool contains(const Eigen::Vector2d& p, double tol = 1e-12) const;
  /// Closest point of the polygon (boundary or interior) to p.
  Eigen::Vector2d closest(const Eigen::Vector2d& p) const;
};

/// The 4 corners of a sole shrunk by `margin` on every side, in the world (x, y), CCW.
std::array<Eigen::Vector2d, 4> soleCorners(const Sole& s, const Eigen::Isometry3d& X_WS,
                                           double margin);

/// Convex hull of the given points (n <= 32).
Polygon convexHull(const Eigen::Vector2d* pts, int n);

struct Distribution {
  double alpha = 1.0;  ///< share of the normal force carried by the right foot (0..1)
  /// CoP of [right, left] in the world (x, y).
  std::array<Eigen::Vector2d, 2> cop_world{{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()}};
  /// Sole axes, about the sole origin.
  std::array<core::Wrench, 2> wrench{
      {core::Wrench::zero(core::Axes::kSole), core::Wrench::zero(core::Axes::kSole)}};
  Eigen::Vector2d zmp{Eigen::Vector2d::Zero()};  ///< realised ZMP (force-weighted mean of the CoPs)
  double error = 0.0;    ///< |realised - requested ZMP|, m (0 when the request is reachable)
  bool clamped = false;  ///< the requested ZMP was outside what the soles can realise
};

/// Splits the total contact force `force` (world, N) acting at the desired ZMP `zmp` (world x, y;
/// no horizontal moment about it; vertical moment mz) between the feet in contact.
/// `sole_pose` are the sole frames (world; soles assumed on the ground plane z = sole z).
/// `alpha_pref` is the preferred right share (e.g. the plan's) used when the ZMP allows it.
Distribution distributeWrench(const Eigen::Vector2d& zmp, const Eigen::Vector3d& force, double mz,
                              const std::array<bool, 2>& contact,
                              const std::array<Eigen::Isometry3d, 2>& sole_pose,
                              const std::array<Sole, 2>& sole, double margin, double min_force,
                              double alpha_pref);

}  // namespace overstep::stabilizer
