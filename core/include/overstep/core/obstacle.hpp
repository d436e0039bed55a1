#pragma once
/// \file
/// The obstacle to step over: a bar lying across the path (axis along y, the robot walks along +x).
/// Shared by the planner and the simulator. Sizes are the clearance envelope including the safety
/// margin (the seed's convention); `margin` adds more on every side.

#include <string>

namespace overstep::core {

struct ObstacleSpec {
  enum class Shape { Box, Cylinder };
  Shape shape = Shape::Box;
  double height = 0.20;  ///< m, top of the envelope above the ground
  double width = 0.11;   ///< m, extent along x (a cylinder's diameter)
  double length = 1.0;   ///< m, extent along y
  double gap = 0.03;     ///< m, from the start toes (sole front edge) to the near face
  double margin = 0.0;   ///< m, extra clearance added to height and to each side in x

  /// Near face (x) in the world frame given the x of the start toes.
  double nearX(double toes_x) const { return toes_x + gap - margin; }
  double farX(double toes_x) const { return toes_x + gap + width + margin; }
  double envelopeHeight() const { return height + margin; }
  double envelopeWidth() const { return width + 2.0 * margin; }
};

/// "box" | "cylinder" -> Shape; throws InputError otherwise.
ObstacleSpec::Shape parseObstacleShape(const std::string& name);
const char* obstacleShapeName(ObstacleSpec::Shape shape);

/// Throws InputError (one line naming the field) for non-finite, non-positive height/width/length,
/// negative gap or margin, any of them above 100 m, or a cylinder whose diameter exceeds its
/// height.
void validate(const ObstacleSpec& spec);

}  // namespace overstep::core
