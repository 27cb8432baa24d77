// Mass properties of the URDF builder (urdf_model.cpp): a solid shape's
// mass and inertia at a density (links without <inertial>), and summing
// rigid parts into a body (links merged over fixed joints).
#pragma once

#include "Simbody.h"

#include <functional>
#include <string>
#include "contact/contact_geometry.hpp"
#include "urdf_model.hpp"

namespace manibench {
namespace scene_detail {

// Mass, centre of mass and central inertia (shape frame) of a solid shape.
void calcShapeMass(const ShapeGeometry& g, double density, double& m, SimTK::Vec3& com, SimTK::Mat33& Ic);

// Adds a rigid part of mass m, centre of mass com_B and central inertia
// Ic_B (both in the body frame) to the body's mass properties (unchecked:
// checkBodyMasses checks the sums).
void addMass(BodyModel& body, double m, const SimTK::Vec3& com_B, const SimTK::Mat33& Ic_B);

// After every link is added: each body's summed inertia must be valid (a
// fixed-joint child's inertia counts only merged into its body), and a
// body that moves must have mass or a body with mass below it (a massless
// moving leaf is not physical: one fell through the ground at t = 1.46 s);
// a massless one with mass below it becomes `massless`. Sets each body's
// inertia; the error names the link and calls `fail` (which throws).
void checkBodyMasses(ArticulationModel& model, const std::function<void(const std::string&)>& fail);

}  // namespace scene_detail
}  // namespace manibench
