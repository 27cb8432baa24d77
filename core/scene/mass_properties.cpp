#include "mass_properties.hpp"

#include <manibench/sdk/numbers.hpp>

#include <sstream>

namespace manibench {
namespace scene_detail {

using SimTK::Inertia;
using SimTK::Mat33;
using SimTK::SymMat33;
using SimTK::Vec3;

using sdk::kPi;

namespace {

SymMat33 toSymmetric(const Mat33& m) {
  return SymMat33().setFromLower(0.5 * (m + ~m));
}

}  // namespace

void calcShapeMass(const ShapeGeometry& g, double density, double& m, Vec3& com, Mat33& Ic) {
  com = Vec3(0);
  Vec3 moments(0);
  const double r = g.radius, l = 2 * g.half_length;
  switch (g.kind) {
    case ShapeKind::Sphere:
      m = density * 4.0 / 3.0 * kPi * r * r * r;
      moments = Vec3(0.4 * m * r * r);
      break;
    case ShapeKind::Box: {
      const Vec3 d = 2 * g.half;
      m = density * d[0] * d[1] * d[2];
      moments = m / 12 * Vec3(d[1] * d[1] + d[2] * d[2], d[0] * d[0] + d[2] * d[2],
                              d[0] * d[0] + d[1] * d[1]);
      break;
    }
    case ShapeKind::Cylinder: {
      m = density * kPi * r * r * l;
      const double side = m * (3 * r * r + l * l) / 12;
      moments = Vec3(side, side, 0.5 * m * r * r);
      break;
    }
    case ShapeKind::Capsule: {
      // A cylinder plus two hemispheres (each with its centroid 3r/8 from
      // its flat face and central inertia 83/320 m r^2 about a transverse axis).
      const double m_cylinder = density * kPi * r * r * l;
      const double m_half = density * 2.0 / 3.0 * kPi * r * r * r;
      const double offset = g.half_length + 3 * r / 8;
      const double side = m_cylinder * (3 * r * r + l * l) / 12 +
                          2 * m_half * (83.0 / 320.0 * r * r + offset * offset);
      m = m_cylinder + 2 * m_half;
      moments = Vec3(side, side, 0.5 * m_cylinder * r * r + 0.4 * 2 * m_half * r * r);
      break;
    }
    case ShapeKind::Convex:
      m = density * g.hull->volume;
      com = g.hull->centroid;
      Ic = density * g.hull->unit_inertia;
      return;
    case ShapeKind::HalfSpace:
      m = 0;
      break;
  }
  Ic = Mat33(moments[0], 0, 0, 0, moments[1], 0, 0, 0, moments[2]);
}

void addMass(BodyModel& body, double m, const Vec3& com_B, const Mat33& Ic_B) {
  if (m <= 0) return;
  body.mass += m;
  body.first_moment += m * com_B;
  // As Inertia(Ic).shiftFromMassCenter(com, m), without its check.
  body.inertia_sum += toSymmetric(Ic_B) + Inertia::pointMassAt(com_B, m).asSymMat33();
}

void checkBodyMasses(ArticulationModel& model,
                     const std::function<void(const std::string&)>& fail) {
  // The mass of each body with everything below it (bodies come parents
  // first, so children are summed before their parent is read).
  std::vector<double> subtree_mass(model.bodies.size(), 0);
  for (std::size_t b = model.bodies.size(); b-- > 0;) {
    subtree_mass[b] += std::max(model.bodies[b].mass, 0.0);
    if (model.bodies[b].parent >= 0) subtree_mass[std::size_t(model.bodies[b].parent)] += subtree_mass[b];
  }
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    BodyModel& body = model.bodies[b];
    const std::string& link = model.links[std::size_t(body.link)].name;
    if (!Inertia::isValidInertiaMatrix(body.inertia_sum)) {
      std::ostringstream s;
      if (!body.invalid_part.empty())
        s << body.invalid_part << ", and so has its body with the links welded to it";
      else
        s << "the body of link '" << link << "' (with the links welded to it) has an invalid inertia";
      s << ": moments must be non-negative and obey the triangle inequality";
      fail(s.str());
    }
    body.inertia = Inertia(body.inertia_sum);
    if (body.joint < 0 || body.massless || body.mass > 0) continue;
    // A massless link between two joints (PartNet's link_N_helper under a
    // slider+ part, a hand's thumb base) is a valid articulation when
    // something with mass hangs below it: that mass gives its joint inertia.
    // Simbody takes it as Body::Massless, as it takes a planar joint's chain.
    if (subtree_mass[b] > 0) {
      body.massless = true;
      continue;
    }
    fail("link '" + link + "' moves (joint '" + model.joints[std::size_t(body.joint)].name +
         "') but neither it nor anything below it has mass: give it an <inertial> or collision "
         "geometry (a moving body without mass is not physical)");
  }
}

}  // namespace scene_detail
}  // namespace manibench
