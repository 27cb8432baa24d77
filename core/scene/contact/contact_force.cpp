#include "contact/contact_force.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <utility>

namespace manibench {
namespace scene_detail {
namespace {

using SimTK::SpatialVec;
using SimTK::Transform;
using SimTK::Vec3;

// Simbody's quintic step: 0 at x <= 0, 1 at x >= 1, smooth in between.
double step5(double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  const double x3 = x * x * x;
  return x3 * (10 + x * (6 * x - 15));
}

// The lowest point of the box [lo, hi] along direction n.
double calcLowestAlong(const Vec3& n, const Vec3& lo, const Vec3& hi) {
  double low = 0;
  for (int k = 0; k < 3; ++k) low += n[k] * (n[k] >= 0 ? lo[k] : hi[k]);
  return low;
}

std::uint64_t pairKey(int a, int b) {
  return static_cast<std::uint64_t>(a) << 32 | static_cast<std::uint32_t>(b);
}

// The anchor of `feature` among the pair's previous ones [begin, end), if
// one lies within `match_distance` of where the point is now on B.
const FrictionAnchor* findAnchor(const std::vector<FrictionAnchor>& previous, std::size_t begin,
                                 std::size_t end, std::int32_t feature, const Vec3& on_b,
                                 double match_distance) {
  for (std::size_t k = begin; k < end; ++k)
    if (previous[k].feature == feature &&
        (previous[k].on_b - on_b).normSqr() < match_distance * match_distance)
      return &previous[k];
  return nullptr;
}

// One contact point's force law, as the linearization needs it.
struct PointLaw {
  double k, kt, ct;  // normal stiffness, friction spring and damper (weighted)
  double c, depth, approach, limit;
};

// The point's linearization for the implicit stepper. Normal: fn n with
// fn = k d (1 + 1.5 c ddot), d falling by n.x. Tangential: -kt stretch -
// ct slip while it sticks; sliding (|ft| past the limit), the capped force
// turns with them but keeps its size. `ft` is the uncapped tangential force.
void fillCoupling(const Vec3& at, const Vec3& n, const PointLaw& law, const Vec3& ft,
                  PointCoupling& point) {
  const double ft_norm = ft.norm();
  const bool sliding = ft_norm > law.limit;
  point.point = Eigen::Vector3d(at[0], at[1], at[2]);
  const Eigen::Vector3d normal_axis(n[0], n[1], n[2]);
  const Eigen::Matrix3d normal = normal_axis * normal_axis.transpose();
  Eigen::Matrix3d tangent = Eigen::Matrix3d::Identity() - normal;
  double tangent_scale = 1;
  if (sliding && ft_norm > 0) {
    const Eigen::Vector3d direction(ft[0] / ft_norm, ft[1] / ft_norm, ft[2] / ft_norm);
    tangent -= direction * direction.transpose();
    tangent_scale = law.limit / ft_norm;
  }
  const double k = law.k, kt = law.kt, ct = law.ct, limit = law.limit;
  const double approach = law.approach;
  point.damping = (1.5 * k * law.c * law.depth) * normal + (tangent_scale * ct) * tangent;
  point.stiffness = (k * (1 + 1.5 * law.c * approach)) * normal + (tangent_scale * kt) * tangent;
  if (sliding && ft_norm > 0) {
    const Eigen::Matrix3d full_tangent = Eigen::Matrix3d::Identity() - normal;
    point.sliding = true;
    point.stick_force = Eigen::Vector3d(ft[0], ft[1], ft[2]);
    point.slide_force = (limit / ft_norm) * point.stick_force;
    point.tangent_damping = ct * full_tangent;
    point.tangent_stiffness = kt * full_tangent;
    point.stick_damping = (1.5 * k * law.c * law.depth) * normal + point.tangent_damping;
    point.stick_stiffness = (k * (1 + 1.5 * law.c * approach)) * normal + point.tangent_stiffness;
    point.limit = limit;
  }
}

}  // namespace

std::ostream& operator<<(std::ostream& out, const FrictionAnchorSet& set) {
  return out << "FrictionAnchorSet(" << set.anchors.size() << " anchors)";
}

ContactForce::ContactForce(const SimTK::SimbodyMatterSubsystem& matter,
                           const SimTK::GeneralForceSubsystem& forces,
                           std::vector<ContactShape> shapes, std::vector<char> self_collision,
                           const FrictionLaw& law)
    : matter_(matter),
      forces_(forces),
      shapes_(std::move(shapes)),
      self_collision_(std::move(self_collision)),
      law_(law) {
  shape_body_.assign(shapes_.size(), -1);
  for (std::size_t i = 0; i < shapes_.size(); ++i) {
    const ContactShape& shape = shapes_[i];
    assert(shape.articulation < static_cast<int>(self_collision_.size()));
    assert(shape.inverse_mass >= 0);
    const bool on_ground = shape.body == SimTK::GroundIndex;
    parent_.push_back(on_ground ? SimTK::MobilizedBodyIndex()
                                : matter_.getMobilizedBody(shape.body)
                                      .getParentMobilizedBody()
                                      .getMobilizedBodyIndex());
    const bool half_space = shape.geometry.kind == ShapeKind::HalfSpace;
    (half_space ? half_spaces_ : finite_).push_back(static_cast<int>(i));
    if (on_ground) continue;
    int b = 0;
    while (b < static_cast<int>(bodies_.size()) &&
           bodies_[b].mobod->getMobilizedBodyIndex() != shape.body)
      ++b;
    if (b == static_cast<int>(bodies_.size())) {
      bodies_.emplace_back();
      bodies_.back().mobod = &matter_.getMobilizedBody(shape.body);
    }
    BodyShapes& body = bodies_[b];
    body.shapes.push_back(static_cast<int>(i));
    shape_body_[i] = b;
    if (half_space) {
      body.has_half_space = true;
      continue;
    }
    Vec3 lo, hi;
    shape.geometry.calcBoundingBox(shape.X_BS, lo, hi);
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p((corner & 1) ? hi[0] : lo[0], (corner & 2) ? hi[1] : lo[1],
                   (corner & 4) ? hi[2] : lo[2]);
      body.radius = std::max(body.radius, p.norm());
    }
  }
  X_ref_.resize(bodies_.size());
  ref_valid_.assign(bodies_.size(), 0);
  X_GB_.resize(bodies_.size());
  fat_lo_.resize(shapes_.size());
  fat_hi_.resize(shapes_.size());
  for (std::size_t i = 0; i < shapes_.size(); ++i)
    if (shape_body_[i] < 0) calcGrownBox(static_cast<int>(i), shapes_[i].X_BS);  // fixed for good
  shape_stamp_.assign(shapes_.size(), 0);
  X_GS_.resize(shapes_.size());
  lo_.resize(shapes_.size());
  hi_.resize(shapes_.size());
  order_ = finite_;
}

ContactForce::~ContactForce() = default;

void ContactForce::realizeTopology(SimTK::State& state) const {
  anchors_index_ = forces_.allocateAutoUpdateDiscreteVariable(
      state, SimTK::Stage::Dynamics, new SimTK::Value<FrictionAnchorSet>(), SimTK::Stage::Velocity);
}

const FrictionAnchorSet& ContactForce::getAnchors(const SimTK::State& state) const {
  return forces_.getDiscreteVariable(state, anchors_index_).getValue<FrictionAnchorSet>();
}

void ContactForce::setAnchors(SimTK::State& state, FrictionAnchorSet anchors) const {
  forces_.updDiscreteVariable(state, anchors_index_).updValue<FrictionAnchorSet>() =
      std::move(anchors);
}

ContactForce::PairMaterial ContactForce::combine(const ContactMaterial& a,
                                                 const ContactMaterial& b) {
  PairMaterial m;
  const double k_sum = a.stiffness + b.stiffness;
  m.k = a.stiffness * b.stiffness / k_sum;
  m.c = (a.dissipation * b.stiffness + b.dissipation * a.stiffness) / k_sum;
  m.mu_static = std::sqrt(a.static_friction * b.static_friction);
  m.mu_dynamic = std::sqrt(a.dynamic_friction * b.dynamic_friction);
  m.mu_viscous = std::sqrt(a.viscous_friction * b.viscous_friction);
  return m;
}

bool ContactForce::isPairAllowed(int i, int j) const {
  const ContactShape& a = shapes_[i];
  const ContactShape& b = shapes_[j];
  if (a.body == b.body) return false;  // also: everything fixed to Ground
  if (a.articulation >= 0 && a.articulation == b.articulation) {
    if (!self_collision_[a.articulation]) return false;
    // Links joined by a joint always overlap at the joint.
    if ((parent_[i].isValid() && parent_[i] == b.body) ||
        (parent_[j].isValid() && parent_[j] == a.body))
      return false;
  }
  return true;
}

void ContactForce::calcGrownBox(int i, const Transform& X_GS) const {
  shapes_[i].geometry.calcBoundingBox(X_GS, fat_lo_[i], fat_hi_[i]);
  fat_lo_[i] -= Vec3(kBroadPhaseMargin);
  fat_hi_[i] += Vec3(kBroadPhaseMargin);
}

void ContactForce::updateCandidates(const SimTK::State& state) const {
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    const BodyShapes& body = bodies_[b];
    const Transform& X = body.mobod->getBodyTransform(state);
    X_GB_[b] = X;
    if (ref_valid_[b] && !body.has_half_space) {
      const Transform& X_ref = X_ref_[b];
      const double moved = (X.p() - X_ref.p()).norm() +
                           (X.R().asMat33() - X_ref.R().asMat33()).norm() * body.radius;
      // The slack covers rounding in the boxes.
      if (moved + 1e-9 <= kBroadPhaseMargin) continue;
    }
    X_ref_[b] = X;
    ref_valid_[b] = 1;
    candidates_valid_ = false;
    for (int i : body.shapes) calcGrownBox(i, X * shapes_[i].X_BS);
  }
  if (!candidates_valid_) {
    findCandidates();
    candidates_valid_ = true;
  }
}

// Half spaces against every finite shape whose box reaches below them;
// finite shapes among themselves by sweep and prune along the axis where
// they spread most. Sorted, so that contact order (and with it every
// floating-point sum) depends only on the state.
void ContactForce::findCandidates() const {
  candidates_.clear();
  for (int h : half_spaces_) {
    const bool moving = shape_body_[h] >= 0;
    const Transform X_GH = moving ? X_ref_[shape_body_[h]] * shapes_[h].X_BS : shapes_[h].X_BS;
    const Vec3 n = X_GH.z();
    const double plane = SimTK::dot(X_GH.p(), n);
    for (int i : finite_) {
      if (!isPairAllowed(h, i)) continue;
      // A moving plane: every shape.
      if (moving || calcLowestAlong(n, fat_lo_[i], fat_hi_[i]) < plane)
        candidates_.emplace_back(std::min(h, i), std::max(h, i));
    }
  }
  if (finite_.size() > 1) {
    Vec3 mean(0), mean_sq(0);
    for (int i : finite_) {
      const Vec3 c = (fat_lo_[i] + fat_hi_[i]) / 2;
      mean += c;
      mean_sq += c.elementwiseMultiply(c);
    }
    const double count = static_cast<double>(finite_.size());
    const Vec3 variance = mean_sq / count - (mean / count).elementwiseMultiply(mean / count);
    int axis = variance[0] >= variance[1] ? 0 : 1;
    if (variance[2] > variance[axis]) axis = 2;
    // Insertion sort: the order of the previous rebuild is nearly right.
    auto before = [&](int a, int b) {
      return fat_lo_[a][axis] < fat_lo_[b][axis] ||
             (fat_lo_[a][axis] == fat_lo_[b][axis] && a < b);
    };
    for (std::size_t n = 1; n < order_.size(); ++n) {
      const int v = order_[n];
      std::size_t m = n;
      for (; m > 0 && before(v, order_[m - 1]); --m) order_[m] = order_[m - 1];
      order_[m] = v;
    }
    const int other1 = (axis + 1) % 3, other2 = (axis + 2) % 3;
    for (std::size_t p = 0; p < order_.size(); ++p) {
      const int i = order_[p];
      for (std::size_t q = p + 1; q < order_.size(); ++q) {
        const int j = order_[q];
        if (fat_lo_[j][axis] > fat_hi_[i][axis]) break;
        if (fat_lo_[j][other1] > fat_hi_[i][other1] || fat_lo_[i][other1] > fat_hi_[j][other1] ||
            fat_lo_[j][other2] > fat_hi_[i][other2] || fat_lo_[i][other2] > fat_hi_[j][other2])
          continue;
        if (isPairAllowed(i, j)) candidates_.emplace_back(std::min(i, j), std::max(i, j));
      }
    }
  }
  std::sort(candidates_.begin(), candidates_.end());
}

void ContactForce::ensureShapeBox(int i) const {
  if (shape_stamp_[i] == evaluation_) return;
  shape_stamp_[i] = evaluation_;
  const int b = shape_body_[i];
  X_GS_[i] = b < 0 ? shapes_[i].X_BS : X_GB_[b] * shapes_[i].X_BS;
  shapes_[i].geometry.calcBoundingBox(X_GS_[i], lo_[i], hi_[i]);
}

// Exactly the pairs whose current boxes overlap (a plane: whose box reaches
// below it) go on to the narrow phase.
bool ContactForce::areBoxesTouching(int ia, int ib) const {
  ensureShapeBox(ia);
  ensureShapeBox(ib);
  const bool a_is_plane = shapes_[ia].geometry.kind == ShapeKind::HalfSpace;
  if (a_is_plane || shapes_[ib].geometry.kind == ShapeKind::HalfSpace) {
    const int h = a_is_plane ? ia : ib, i = a_is_plane ? ib : ia;
    const Vec3 n = X_GS_[h].z();
    return calcLowestAlong(n, lo_[i], hi_[i]) < SimTK::dot(X_GS_[h].p(), n);
  }
  return !(lo_[ib][0] > hi_[ia][0] || lo_[ia][0] > hi_[ib][0] || lo_[ib][1] > hi_[ia][1] ||
           lo_[ia][1] > hi_[ib][1] || lo_[ib][2] > hi_[ia][2] || lo_[ia][2] > hi_[ib][2]);
}

// The pair's combined material, its stiffnesses capped so that no point of
// `points` oscillates above law_.max_frequency on the pair's share of mass.
ContactForce::PairMaterial ContactForce::calcPairMaterial(const ContactShape& a,
                                                          const ContactShape& b,
                                                          std::size_t points) const {
  PairMaterial material = combine(a.material, b.material);
  material.friction_stiffness = law_.stiffness;
  material.friction_damping = law_.damping;
  const double inverse_mass = a.inverse_mass + b.inverse_mass;
  if (law_.max_frequency > 0 && inverse_mass > 0) {
    const double share = 1 / (inverse_mass * std::max<double>(4, static_cast<double>(points)));
    const double w = law_.max_frequency;
    material.k = std::min(material.k, share * w * w);
    material.friction_stiffness = std::min(material.friction_stiffness, share * w * w);
    material.friction_damping = std::min(material.friction_damping, share * w);
  }
  return material;
}

double ContactForce::evaluate(const SimTK::State& state, Mode mode,
                              SimTK::Vector_<SpatialVec>* body_forces,
                              std::vector<Report>* reports) const {
  const bool dynamic = mode != Mode::Energy;  // needs velocities
  ++evaluation_;
  updateCandidates(state);

  const std::vector<FrictionAnchor>& previous =
      forces_.getDiscreteVariable(state, anchors_index_).getValue<FrictionAnchorSet>().anchors;
  std::vector<FrictionAnchor>* next = nullptr;
  if (mode == Mode::Apply) {
    next = &forces_.updDiscreteVarUpdateValue(state, anchors_index_)
                .updValue<FrictionAnchorSet>()
                .anchors;
    next->clear();
    linearization_.clear();
  }
  const bool linearize = mode == Mode::Apply && keep_linearization_;
  std::size_t cursor = 0;  // into `previous`, which is sorted like candidates_
  double energy = 0;

  for (const auto& [ia, ib] : candidates_) {
    if (!areBoxesTouching(ia, ib)) continue;
    narrow_.calcContacts(shapes_[ia].geometry, X_GS_[ia], shapes_[ib].geometry, X_GS_[ib],
                         manifold_);
    if (manifold_.empty()) continue;
    const ContactShape& a = shapes_[ia];
    const ContactShape& b = shapes_[ib];
    const PairMaterial material = calcPairMaterial(a, b, manifold_.size());
    const double friction_stiffness = material.friction_stiffness;
    const double friction_damping = material.friction_damping;
    const SimTK::MobilizedBody& body_a = matter_.getMobilizedBody(a.body);
    const SimTK::MobilizedBody& body_b = matter_.getMobilizedBody(b.body);
    const Transform& X_GA = body_a.getBodyTransform(state);
    const Transform& X_GB = body_b.getBodyTransform(state);
    const SpatialVec zero(Vec3(0), Vec3(0));
    const SpatialVec& V_A = dynamic ? body_a.getBodyVelocity(state) : zero;
    const SpatialVec& V_B = dynamic ? body_b.getBodyVelocity(state) : zero;

    const std::uint64_t key = pairKey(ia, ib);
    while (cursor < previous.size() && previous[cursor].pair < key) ++cursor;
    std::size_t end = cursor;
    while (end < previous.size() && previous[end].pair == key) ++end;
    const std::size_t first_new = next != nullptr ? next->size() : 0;

    for (const ContactPoint& c : manifold_) {
      const Vec3 n(c.normal);
      const Vec3 on_b = ~X_GB * c.point;
      const FrictionAnchor* anchor =
          findAnchor(previous, cursor, end, c.feature, on_b, law_.match_distance);
      // Tangential stretch of the anchor spring.
      Vec3 stretch(0);
      if (anchor != nullptr) {
        stretch = X_GB * anchor->on_b - X_GA * anchor->on_a;
        stretch -= SimTK::dot(stretch, n) * n;
      }
      const double k = c.weight * material.k;
      const double kt = c.weight * friction_stiffness;
      if (mode == Mode::Energy) {
        energy += 0.5 * k * c.depth * c.depth + 0.5 * kt * stretch.normSqr();
        continue;
      }

      const Vec3 v_a = V_A[1] + SimTK::cross(V_A[0], c.point - X_GA.p());
      const Vec3 v_b = V_B[1] + SimTK::cross(V_B[0], c.point - X_GB.p());
      const Vec3 v = v_b - v_a;
      const double approach = -SimTK::dot(v, n);  // d(depth)/dt
      const double fn = k * c.depth * (1 + 1.5 * material.c * approach);
      if (fn <= 0) continue;  // separating fast: no force, anchor released

      const double ct = c.weight * friction_damping;
      const Vec3 slip = v - SimTK::dot(v, n) * n;
      const double slip_speed = slip.norm();
      Vec3 ft = -kt * stretch - ct * slip;
      const double mu = material.mu_static -
                        (material.mu_static - material.mu_dynamic) *
                            step5(slip_speed / (3 * law_.transition_speed)) +
                        material.mu_viscous * slip_speed;
      const double limit = mu * fn;
      const double ft_norm = ft.norm();
      Vec3 new_stretch = stretch;
      const bool sliding = ft_norm > limit;
      if (linearize) {
        PointCoupling& point = linearization_.emplace_back();
        point.body_a = a.body;
        point.body_b = b.body;
        fillCoupling(c.point, n, PointLaw{k, kt, ct, material.c, c.depth, approach, limit}, ft,
                     point);
      }
      if (sliding) {
        // Sliding: cap the force, and move the anchor so that the spring
        // alone would give the capped force.
        ft *= limit / ft_norm;
        new_stretch = -(ft + ct * slip) / kt;
        const double stretch_norm = new_stretch.norm(), max_stretch = limit / kt;
        if (stretch_norm > max_stretch) new_stretch *= max_stretch / stretch_norm;
      }
      const Vec3 f = fn * n + ft;  // on B
      if (body_forces != nullptr) {
        if (b.body != SimTK::GroundIndex)
          (*body_forces)[b.body] += SpatialVec(SimTK::cross(c.point - X_GB.p(), f), f);
        if (a.body != SimTK::GroundIndex)
          (*body_forces)[a.body] -= SpatialVec(SimTK::cross(c.point - X_GA.p(), f), f);
      }
      if (next != nullptr)
        next->push_back(FrictionAnchor{key, c.feature, ~X_GA * (c.point - new_stretch), on_b});
      if (reports != nullptr) reports->push_back(Report{ia, ib, c.point, f});
    }
    if (next != nullptr)
      std::sort(
          next->begin() + static_cast<std::ptrdiff_t>(first_new), next->end(),
          [](const FrictionAnchor& x, const FrictionAnchor& y) { return x.feature < y.feature; });
    cursor = end;
  }
  if (mode == Mode::Apply) forces_.markDiscreteVarUpdateValueRealized(state, anchors_index_);
  return energy;
}

void ContactForce::addImplicitTerms(const SimTK::State&, ImplicitTerms& terms) const {
  assert(keep_linearization_);
  terms.points.insert(terms.points.end(), linearization_.begin(), linearization_.end());
}

void ContactForce::calcForce(const SimTK::State& state, SimTK::Vector_<SpatialVec>& body_forces,
                             SimTK::Vector_<Vec3>&, SimTK::Vector&) const {
  evaluate(state, Mode::Apply, &body_forces, nullptr);
}

SimTK::Real ContactForce::calcPotentialEnergy(const SimTK::State& state) const {
  return evaluate(state, Mode::Energy, nullptr, nullptr);
}

void ContactForce::calcReports(const SimTK::State& state, std::vector<Report>& reports) const {
  reports.clear();
  evaluate(state, Mode::Report, nullptr, &reports);
}

}  // namespace scene_detail
}  // namespace manibench
