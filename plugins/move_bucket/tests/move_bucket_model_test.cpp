// MoveBucket-v0's model library (plugins/move_bucket): mesh geometry and
// mass properties, the procedural buckets (ids, splits, convex pieces,
// mass, bail, mesh files) and the staged reward, checked directly through
// the family's header.
#include <gtest/gtest.h>


#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <unistd.h>

#include "move_bucket.hpp"

namespace {

namespace bk = move_bucket;
using manibench::sdk::kPi;

std::vector<std::string> allBuckets() {
  std::vector<std::string> ids = bk::listGeneratedBuckets("train");
  for (const std::string& id : bk::listGeneratedBuckets("test")) ids.push_back(id);
  return ids;
}

// Whether `p` lies inside the convex mesh by more than `margin`.
bool isInside(const bk::TriangleMesh& piece, const Eigen::Vector3d& p, double margin) {
  for (const auto& t : piece.triangles) {
    const Eigen::Vector3d& a = piece.vertices[t[0]];
    const Eigen::Vector3d n = (piece.vertices[t[1]] - a).cross(piece.vertices[t[2]] - a).normalized();
    if (n.dot(p - a) > -margin) return false;
  }
  return true;
}

// ---- geometry -----------------------------------------------------------------

TEST(MoveBucketGeometry, LoftMassPropertiesMatchClosedForms) {
  // A 1 x 2 x 3 box as a loft: mass, centre and principal inertias.
  const std::vector<Eigen::Vector2d> rect = {{0, 0}, {1, 0}, {1, 2}, {0, 2}};
  const bk::MassProperties box = bk::calcMassProperties(bk::makeLoft(rect, 0, rect, 3), 2.0);
  EXPECT_NEAR(box.mass, 12.0, 1e-12);
  EXPECT_NEAR((box.com - Eigen::Vector3d(0.5, 1, 1.5)).norm(), 0, 1e-12);
  EXPECT_NEAR(box.inertia(0, 0), 12.0 / 12 * (4 + 9), 1e-10);
  EXPECT_NEAR(box.inertia(1, 1), 12.0 / 12 * (1 + 9), 1e-10);
  EXPECT_NEAR(box.inertia(2, 2), 12.0 / 12 * (1 + 4), 1e-10);
  EXPECT_NEAR(box.inertia(0, 1), 0, 1e-10);
  // Clockwise rings give the same solid; a frustum of a square pyramid has
  // volume h/3 (A1 + A2 + sqrt(A1 A2)).
  const std::vector<Eigen::Vector2d> big = {{-1, -1}, {-1, 1}, {1, 1}, {1, -1}};
  const std::vector<Eigen::Vector2d> small = {{-0.5, -0.5}, {-0.5, 0.5}, {0.5, 0.5}, {0.5, -0.5}};
  EXPECT_NEAR(bk::calcMassProperties(bk::makeLoft(big, 0, small, 1), 1).mass, (4 + 1 + 2) / 3.0, 1e-12);
  // Two boxes combine with the parallel-axis theorem: one 2-long box.
  const bk::MassProperties half = bk::calcMassProperties(bk::makeLoft(rect, 0, rect, 1.5), 2.0);
  bk::MassProperties upper = half;
  upper.com.z() += 1.5;
  const bk::MassProperties both = bk::combine({half, upper});
  EXPECT_NEAR((both.inertia - box.inertia).norm(), 0, 1e-9);
}

TEST(MoveBucketGeometry, ObjTextAndSurfaceSamples) {
  const std::vector<Eigen::Vector2d> rect = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const bk::TriangleMesh cube = bk::makeLoft(rect, 0, rect, 1);
  const std::string obj = bk::writeObj(cube, "cube", /*smooth=*/true);
  std::istringstream in(obj);
  int v = 0, vn = 0, f = 0;
  for (std::string line; std::getline(in, line);) {
    v += line.rfind("v ", 0) == 0;
    vn += line.rfind("vn ", 0) == 0;
    f += line.rfind("f ", 0) == 0;
    if (line.rfind("vn ", 0) == 0) {  // creases stay sharp: every normal is an axis
      std::istringstream n(line.substr(3));
      Eigen::Vector3d normal;
      n >> normal.x() >> normal.y() >> normal.z();
      EXPECT_NEAR(normal.cwiseAbs().maxCoeff(), 1.0, 1e-9) << line;
    }
  }
  EXPECT_EQ(v, 8);
  EXPECT_EQ(f, 12);
  EXPECT_EQ(vn, 36);
  EXPECT_NEAR(cube.calcArea(), 6.0, 1e-12);
  for (const Eigen::Vector3d& p : bk::sampleSurface(cube, 500, 7)) {
    EXPECT_TRUE((p.array() >= -1e-12).all() && (p.array() <= 1 + 1e-12).all());
    EXPECT_NEAR(std::min(p.minCoeff(), 1 - p.maxCoeff()), 0, 1e-9) << "on a face";
  }
  EXPECT_EQ(bk::sampleSurface(cube, 10, 7), bk::sampleSurface(cube, 10, 7));
}

// ---- generator ------------------------------------------------------------------

TEST(MoveBucketGenerator, SameIdSameBucketAndUnknownIdsAreRefused) {
  EXPECT_EQ(bk::generateBucket("3004").urdf, bk::generateBucket("3004").urdf);
  EXPECT_EQ(bk::generateBucket("3104").files, bk::generateBucket("3104").files);
  std::set<std::string> urdfs;
  for (const std::string& id : allBuckets()) urdfs.insert(bk::generateBucket(id).urdf);
  EXPECT_EQ(urdfs.size(), 40u);
  for (const char* bad : {"3030", "3110", "2999", "abc", ""})
    EXPECT_THROW(bk::generateBucket(bad), manibench::sdk::Error) << bad;
  EXPECT_THROW(bk::listGeneratedBuckets("val"), manibench::sdk::Error);
}

TEST(MoveBucketGenerator, SplitsAreDisjointAndTestShapesAreNewToTraining) {
  const std::vector<std::string> train = bk::listGeneratedBuckets("train"), test = bk::listGeneratedBuckets("test");
  EXPECT_GE(train.size(), 29u);
  EXPECT_GE(test.size(), 10u);
  std::set<std::pair<bk::BucketShape, int>> train_shapes, test_shapes;
  int bails = 0;
  for (const std::string& id : train) {
    EXPECT_EQ(std::count(test.begin(), test.end(), id), 0) << id;
    const bk::BucketParams p = bk::getBucketParams(id);
    train_shapes.insert({p.shape, p.sides});
    bails += p.bail;
  }
  for (const std::string& id : test) {
    const bk::BucketParams p = bk::getBucketParams(id);
    test_shapes.insert({p.shape, p.sides});
    EXPECT_EQ(train_shapes.count({p.shape, p.sides}), 0u) << id << ": a shape training shows";
    bails += p.bail;
  }
  EXPECT_GE(train_shapes.size(), 3u);  // round, hexagonal, octagonal
  EXPECT_GE(test_shapes.size(), 2u);   // square, oval
  EXPECT_GT(bails, 8);
  EXPECT_LT(bails, 32);
}

// The pieces are convex, closed and disjoint enough to be the collision
// shapes, and they are the visual mesh: collision follows the visual shape
// exactly (B.9).
TEST(MoveBucketGenerator, PiecesAreConvexAndAreTheVisualMesh) {
  for (const std::string& id : allBuckets()) {
    const bk::BucketParams p = bk::getBucketParams(id);
    const std::vector<bk::TriangleMesh> pieces = bk::makeBucketPieces(p);
    EXPECT_EQ(pieces.size(), 1 + 2 * std::size_t(p.sides)) << id;
    std::size_t visual_vertices = 0;
    for (const bk::TriangleMesh& piece : pieces) {
      visual_vertices += piece.vertices.size();
      for (const auto& t : piece.triangles) {  // every vertex on the inner side of every face
        const Eigen::Vector3d& a = piece.vertices[t[0]];
        const Eigen::Vector3d n = (piece.vertices[t[1]] - a).cross(piece.vertices[t[2]] - a).normalized();
        for (const Eigen::Vector3d& v : piece.vertices) ASSERT_LE(n.dot(v - a), 1e-12) << id;
      }
      EXPECT_GT(bk::calcMassProperties(piece, 1).mass, 0) << id;
    }
    const bk::BucketModel m = bk::generateBucket(id);
    EXPECT_EQ(m.files.size(), pieces.size() + 1) << id << ": one OBJ per piece and the visual body";
    std::istringstream body(m.files.at("body.obj"));
    std::size_t v = 0;
    for (std::string line; std::getline(body, line);) v += line.rfind("v ", 0) == 0;
    EXPECT_EQ(v, visual_vertices) << id;
    // the grip: a flat face on +-y at the rim's apothem, the rim section
    // (wall + lip) fits the 8 cm finger opening with room to spare
    EXPECT_NEAR(m.rim_outer_y, p.radius + p.lip_width, 1e-9) << id;
    EXPECT_NEAR(m.rim_inner_y, p.radius - p.wall, 1e-9) << id;
    EXPECT_GT(m.rim_outer_y - m.rim_inner_y, 0.01) << id;
    EXPECT_LT(m.rim_outer_y - m.rim_inner_y, 0.03) << id;
    EXPECT_NEAR(m.upper.z(), m.rim_height, 1e-12);
    EXPECT_NEAR(m.lower.z(), 0, 1e-12);
    EXPECT_NEAR(m.floor_height, p.bottom, 1e-12);
    // ManiSkill's scale (~0.3 m) and a ball that fits
    EXPECT_GT(m.rim_height, 0.2) << id;
    EXPECT_LT(m.rim_height, 0.36) << id;
    EXPECT_GT(p.taper * m.rim_inner_y, 1.8 * bk::kBallRadius) << id << ": the ball fits the bottom";
    // two grippers squeezing 35 N (5000 N/m x 7 mm) with friction 1 hold
    // at least twice the weight of bucket and ball
    EXPECT_GT(m.mass, 1.0) << id;
    EXPECT_GT(2 * 2 * 1.0 * 5000 * (m.rim_outer_y - m.rim_inner_y) / 2, 2 * 9.81 * (m.mass + 0.53)) << id;
    for (const Eigen::Vector3d& s : m.surface_points)
      ASSERT_TRUE((s.array() >= m.lower.array() - 1e-9).all() && (s.array() <= m.upper.array() + 1e-9).all());
  }
}

// The bail folds down either way to its limit, past the horizontal, and
// there its wire stays outside every piece of the body and below the rim
// by more than the grippers need (their pads reach 2.1 cm below it).
TEST(MoveBucketGenerator, BailRestsBelowTheRimOutsideTheWalls) {
  int seen = 0;
  for (const std::string& id : allBuckets()) {
    const bk::BucketParams p = bk::getBucketParams(id);
    const bk::BucketModel m = bk::generateBucket(id);
    EXPECT_EQ(p.bail, !m.bail_joint.empty()) << id;
    if (!p.bail) continue;
    ++seen;
    EXPECT_NEAR(m.bail_lower, -m.bail_upper, 1e-12);
    EXPECT_GT(m.bail_upper, kPi / 2) << id;
    const std::vector<bk::TriangleMesh> pieces = bk::makeBucketPieces(p);
    const double zp = p.height - p.bail_drop;
    double reach = 0;  // the bail's radius, from its first wire segment (a chord of pi / 10)
    std::istringstream urdf(m.urdf);
    for (std::string line; std::getline(urdf, line);)
      if (line.find("name=\"bail_0\"") != std::string::npos && line.find("<collision") != std::string::npos) {
        const std::size_t at = line.find("xyz=\"") + 5;
        std::istringstream xyz(line.substr(at));
        Eigen::Vector3d centre;
        xyz >> centre.x() >> centre.y() >> centre.z();
        reach = centre.norm() / std::cos(kPi / 20);
      }
    ASSERT_GT(reach, 0.1) << id;
    for (double q : {m.bail_lower, m.bail_upper})
      for (int i = 0; i <= 40; ++i) {
        const double a = kPi * i / 40;
        const Eigen::Vector3d local(reach * std::cos(a), 0, reach * std::sin(a));
        const Eigen::Vector3d w = Eigen::Vector3d(0, 0, zp) + Eigen::AngleAxisd(q, Eigen::Vector3d::UnitX()) * local;
        EXPECT_LT(w.z(), p.height - 0.03) << id;
        // the wire's surface: points around the centre line at its radius
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
              if (dx == 0 && dy == 0 && dz == 0) continue;
              const Eigen::Vector3d surface = w + p.bail_wire * Eigen::Vector3d(dx, dy, dz).normalized();
              for (std::size_t k = 0; k < pieces.size(); ++k)
                ASSERT_FALSE(isInside(pieces[k], surface, 0)) << id << " q " << q << " piece " << k;
            }
      }
  }
  EXPECT_GT(seen, 5);
}

TEST(MoveBucketGenerator, MeshFilesAreWrittenOnceAndFound) {
  const std::string root = (std::filesystem::temp_directory_path() /
                            ("manibench_bucket_cache_test_" + std::to_string(::getpid())))
                               .string();
  std::filesystem::remove_all(root);
  bk::BucketModel a = bk::generateBucket("3001");
  bk::writeMeshFiles(a, root);
  ASSERT_FALSE(a.base_dir.empty());
  for (const auto& [name, text] : a.files) {
    std::ifstream in(a.base_dir + "/" + name);
    std::stringstream s;
    s << in.rdbuf();
    EXPECT_EQ(s.str(), text) << name;
  }
  const auto written = std::filesystem::last_write_time(a.base_dir + "/body.obj");
  bk::BucketModel again = bk::generateBucket("3001");
  bk::writeMeshFiles(again, root);
  EXPECT_EQ(again.base_dir, a.base_dir);
  EXPECT_EQ(std::filesystem::last_write_time(again.base_dir + "/body.obj"), written) << "not written twice";
  bk::BucketModel other = bk::generateBucket("3002");
  bk::writeMeshFiles(other, root);
  EXPECT_NE(other.base_dir, a.base_dir);
  std::filesystem::remove_all(root);
}

// ---- reward ----------------------------------------------------------------------

bk::RewardInputs sampleStage(std::mt19937& rng, bk::RewardStage stage, bool extreme) {
  std::uniform_real_distribution<double> u(0, 1);
  auto pick = [&](double lo, double hi) {
    if (extreme) return u(rng) < 0.5 ? lo : hi;
    return lo + (hi - lo) * u(rng);
  };
  bk::RewardInputs in;
  in.gripper_distance = pick(0, 3);
  in.height_difference = pick(0, 1);
  in.opposition = pick(0, 2);
  in.tilt = pick(0, kPi);
  in.speed = pick(0, 3);
  in.angular_speed = pick(0, 5);
  in.up_speed = pick(-3, 3);
  in.speed_to_platform = pick(-3, 3);
  in.action_norm = pick(0, 4.5);
  in.platform_distance = pick(0, 3);
  in.lift = pick(-0.3, 0.8);
  using C = bk::RewardConstants;
  switch (stage) {
    case bk::RewardStage::kApproach:
      in.gripper_distance = pick(C::kNear, 3);
      if (std::abs(in.lift - C::kLiftHeight) < C::kLiftTolerance) in.lift = pick(-0.3, C::kLiftHeight - C::kLiftTolerance);
      break;
    case bk::RewardStage::kLift:
      in.gripper_distance = pick(0, C::kNear - 1e-12);
      if (std::abs(in.lift - C::kLiftHeight) < C::kLiftTolerance) in.lift = pick(C::kLiftHeight + C::kLiftTolerance, 0.8);
      break;
    case bk::RewardStage::kCarry:
      in.lift = pick(C::kLiftHeight - C::kLiftTolerance + 1e-9, C::kLiftHeight + C::kLiftTolerance - 1e-9);
      in.platform_distance = pick(C::kOnPlatform + 1e-9, 3);
      break;
    case bk::RewardStage::kHold:
      in.lift = pick(C::kLiftHeight - C::kLiftTolerance + 1e-9, C::kLiftHeight + C::kLiftTolerance - 1e-9);
      in.platform_distance = pick(0, C::kOnPlatform);
      break;
  }
  return in;
}

// C.1: every stage's rewards lie strictly above all rewards of the stage
// before; sampled uniformly and at the corners of every term's range.
TEST(MoveBucketReward, StagesAreStrictlyOrdered) {
  std::mt19937 rng(11);
  double previous_max = -1e300;
  for (bk::RewardStage stage : {bk::RewardStage::kApproach, bk::RewardStage::kLift, bk::RewardStage::kCarry,
                                bk::RewardStage::kHold}) {
    double lo = 1e300, hi = -1e300;
    for (int i = 0; i < 40000; ++i) {
      const bk::RewardInputs in = sampleStage(rng, stage, i % 2 == 0);
      ASSERT_EQ(bk::calcRewardStage(in), stage);
      const double r = bk::calcStagedReward(in);
      ASSERT_TRUE(std::isfinite(r));
      lo = std::min(lo, r);
      hi = std::max(hi, r);
    }
    EXPECT_GT(lo, previous_max) << "stage " << int(stage);
    previous_max = hi;
  }
  EXPECT_LE(previous_max, 80.0);
}

TEST(MoveBucketReward, EachTermPointsTheRightWay) {
  bk::RewardInputs in;
  in.gripper_distance = 0.5;
  const double far = bk::calcStagedReward(in);
  in.gripper_distance = 0.2;
  EXPECT_GT(bk::calcStagedReward(in), far) << "approach";
  in.tilt = 0.3;
  EXPECT_LT(bk::calcStagedReward(in), bk::calcStagedReward(bk::RewardInputs{0.2})) << "tilt";
  // lift stage: opposed grippers, rising, closer to 0.2 m
  bk::RewardInputs lift;
  lift.gripper_distance = 0.02;
  lift.lift = 0.05;
  const double base = bk::calcStagedReward(lift);
  lift.opposition = 2;
  EXPECT_GT(bk::calcStagedReward(lift), base);
  lift.up_speed = 0.2;
  EXPECT_GT(bk::calcStagedReward(lift), base + 4);
  bk::RewardInputs higher = lift;
  higher.lift = 0.12;
  EXPECT_GT(bk::calcStagedReward(higher), bk::calcStagedReward(lift));
  // carry: towards the platform pays, away costs
  bk::RewardInputs carry = lift;
  carry.lift = 0.2;
  carry.platform_distance = 0.8;
  carry.speed_to_platform = 0.3;
  bk::RewardInputs away = carry;
  away.speed_to_platform = -0.3;
  EXPECT_EQ(bk::calcRewardStage(carry), bk::RewardStage::kCarry);
  EXPECT_GT(bk::calcStagedReward(carry), bk::calcStagedReward(away));
  // hold: static and upright pay
  bk::RewardInputs hold = carry;
  hold.platform_distance = 0.1;
  hold.speed = 0.3;
  bk::RewardInputs still = hold;
  still.speed = 0.01;
  EXPECT_EQ(bk::calcRewardStage(hold), bk::RewardStage::kHold);
  EXPECT_GT(bk::calcStagedReward(still), bk::calcStagedReward(hold) + 2);
  bk::RewardInputs tipped = still;
  tipped.tilt = 1.4;
  EXPECT_LT(bk::calcStagedReward(tipped), bk::calcStagedReward(still) - 2 - 0.2 * 1.4);
}

}  // namespace
