#include "overstep/core/obstacle.hpp"

#include <cmath>
#include <cstdio>

#include "overstep/core/error.hpp"

namespace overstep::core {
namespace {

std::string num(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

constexpr double kMaxSize = 100.0;  // m: beyond it the collision library's arithmetic breaks

void positive(double v, const char* name) {
  if (!(v > 0.0 && v <= kMaxSize)) {
    throw InputError(std::string("obstacle ") + name +
                     ": expected a positive length in m (at most " + num(kMaxSize) + "), got " +
                     num(v));
  }
}

void nonNegative(double v, const char* name) {
  if (!(v >= 0.0 && v <= kMaxSize)) {
    throw InputError(std::string("obstacle ") + name + ": expected 0 to " + num(kMaxSize) +
                     " m, got " + num(v));
  }
}

}  // namespace

ObstacleSpec::Shape parseObstacleShape(const std::string& name) {
  if (name == "box") return ObstacleSpec::Shape::Box;
  if (name == "cylinder") return ObstacleSpec::Shape::Cylinder;
  throw InputError("obstacle shape: expected 'box' or 'cylinder', got '" + name + "'");
}

const char* obstacleShapeName(ObstacleSpec::Shape shape) {
  return shape == ObstacleSpec::Shape::Box ? "box" : "cylinder";
}

void validate(const ObstacleSpec& s) {
  positive(s.height, "height");
  positive(s.width, "width");
  positive(s.length, "length");
  nonNegative(s.gap, "gap");
  nonNegative(s.margin, "margin");
  if (s.shape == ObstacleSpec::Shape::Cylinder && s.width > s.height) {
    throw InputError("obstacle: a cylinder's diameter (width " + num(s.width) +
                     " m) cannot exceed its top height (" + num(s.height) + " m)");
  }
}

}  // namespace overstep::core
