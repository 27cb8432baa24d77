// MoveBucket: the dual-arm mobile Panda lifts a bucket with a ball inside and
// sets it upright on a platform (ManiSkill v1, supplement B.2-B.4, B.9,
// C.1.3). Buckets come from a procedural generator (bucket_generator.cpp,
// convex pieces it knows exactly, bucket_geometry.cpp) or from a
// PartNet-Mobility folder (partnet_loader.cpp).
#pragma once

#include <manibench/kit/family.hpp>
#include <manibench/kit/file_cache.hpp>

namespace move_bucket {

using namespace manibench::kit;  // kit/family.hpp

// ---- geometry (bucket_geometry.cpp) -----------------------------------------

// A closed triangle mesh (counterclockwise seen from outside).
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;

  void append(const TriangleMesh& other);
  double calcArea() const;
};

// Mass, centre of mass and inertia about it of a closed mesh of uniform
// density (divergence theorem over its triangles).
struct MassProperties {
  double mass = 0;
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // about com
};
MassProperties calcMassProperties(const TriangleMesh& mesh, double density);
// The sum of several bodies' properties (inertia moved to the common com).
MassProperties combine(const std::vector<MassProperties>& parts);

// An <inertial> element (com origin, mass, inertia about the com).
std::string inertialXml(const MassProperties& m);

// A convex solid between two convex polygons of the same vertex count in
// planes z = z0 and z = z1 (vertex k of one joined to vertex k of the other;
// the generator only makes lofts whose side faces are planar).
TriangleMesh makeLoft(const std::vector<Eigen::Vector2d>& bottom, double z0,
                      const std::vector<Eigen::Vector2d>& top, double z1);

// Wavefront OBJ text of a mesh: `o` name, vertices, per-vertex normals
// (smooth: averaged over the triangles around a vertex, for round outlines;
// flat: one normal per triangle) and faces.
std::string writeObj(const TriangleMesh& mesh, const std::string& name, bool smooth);

// `count` points on the mesh's surface, area-weighted, from `seed`.
std::vector<Eigen::Vector3d> sampleSurface(const TriangleMesh& mesh, std::size_t count, uint64_t seed);

// ---- the bucket model -----------------------------------------------------------

// What the task needs to know about a bucket, generated or loaded. The
// bucket frame (the root link's) has its origin at the centre of the
// bottom's underside, z up; the expert grips the rim where it crosses the
// frame's y axis.
struct BucketModel {
  std::string id;
  std::string urdf;      // URDF text
  std::string base_dir;  // relative mesh paths start here
  // Mesh files the URDF names, relative to base_dir, and their text: the
  // task writes them (MeshCache) before loading the URDF. Empty for
  // PartNet-Mobility buckets, whose files are on disk.
  std::map<std::string, std::string> files;
  std::string body_link = "bucket";  // the link the ball sits in
  // The links whose collision pieces make the body (fixed to body_link; a
  // grip on any of them holds the bucket): body_link alone when empty.
  std::vector<std::string> body_parts;
  // The bail (handle), when the bucket has one: its revolute joint.
  std::string bail_joint;
  double bail_lower = 0, bail_upper = 0;  // rad
  // The body's extent in the bucket frame (visual geometry, bail excluded):
  // the ball is inside while its centre is in this box (B.4).
  Eigen::Vector3d lower = Eigen::Vector3d::Zero(), upper = Eigen::Vector3d::Zero();
  // The rim along the bucket frame's y axis: its height, outer (lip
  // included) and inner half extents; x: the outer half extent.
  double rim_height = 0, rim_outer_y = 0, rim_inner_y = 0, rim_outer_x = 0;
  double floor_height = 0;  // the inside bottom above the bucket frame, m
  double mass = 0;  // body and bail, kg (0 for PartNet buckets: the host computes it)
  // Points on the body's surface (bucket frame) for the reward's
  // gripper-bucket distance (ManiSkill samples the bucket's meshes too).
  std::vector<Eigen::Vector3d> surface_points;
  std::string summary;  // one line
};

// ---- procedural generator (bucket_generator.cpp) -----------------------------

enum class BucketShape { kRound, kPolygon, kOval };

struct BucketParams {
  BucketShape shape = BucketShape::kRound;
  int sides = 24;          // outline vertices (polygon: its sides)
  double height = 0.3;     // underside of the bottom to the rim top, m
  double radius = 0.17;    // rim: outer apothem along y (round, polygon), m
  double aspect = 1.0;     // oval: x semi-axis / y semi-axis
  double taper = 0.85;     // bottom outline scale / rim outline scale
  double wall = 0.006;     // horizontal wall thickness, m
  double bottom = 0.01;    // bottom thickness, m
  double lip_width = 0.01, lip_height = 0.015;  // rim bead outside the wall, m
  bool bail = false;
  double bail_drop = 0.05;      // pivots below the rim top, m
  double bail_wire = 0.004;     // wire radius, m
  std::array<double, 3> color{}, bail_color{};
};

// The parameters of a generated bucket id (throws MB_NOT_FOUND for ids the
// generator does not know); the same id always gives the same bucket.
BucketParams getBucketParams(const std::string& bucket_id);
BucketModel generateBucket(const std::string& bucket_id);
// The convex pieces of a bucket, bucket frame: the bottom slab, then one
// wall piece per outline edge, then one rim-lip piece per edge. They are
// its collision shapes and, together, its visual mesh.
std::vector<TriangleMesh> makeBucketPieces(const BucketParams& params);
BucketModel generateBucket(const std::string& bucket_id, const BucketParams& params);
// Generated bucket ids of a split ("train" or "test").
std::vector<std::string> listGeneratedBuckets(const std::string& split);
std::string toString(BucketShape shape);

// ---- PartNet-Mobility buckets (partnet_loader.cpp) --------------------------

// Loads a PartNet-Mobility bucket with every length multiplied by `scale`:
// body, rim, floor and handle joint measured on its meshes, the URDF given
// a root link in the bucket frame. Errors name the file and what is wrong.
// Every link's collision meshes become convex pieces cached under
// `cache_root` ("": the URDF's meshes as they are, one hull each); the
// body weighs a shell of kShellThickness at kShellDensity over its surface.
constexpr double kShellThickness = 0.004;  // m: a plastic bucket's wall
constexpr double kShellDensity = 1000;     // kg/m^3: ManiSkill v1's bucket density
BucketModel loadPartNetBucket(const std::string& folder, const std::string& id, double scale,
                              const std::string& cache_root = "");

// Writes a model's mesh files under `cache_root` (a folder per bucket and
// content hash, written atomically so that parallel workers agree) and
// points the model's base_dir at it.
void writeMeshFiles(BucketModel& model, const std::string& cache_root);
// (The cache root: the kit's getDefaultCacheRoot, kit/file_cache.hpp.)

// ---- the state observation, shared with the expert --------------------------

// After the robot's part (the kit's AgentState: ManiSkill's agent vector,
// then both TCP poses; experts find its segments by name), the objects'.
struct ObservationLayout {
  static constexpr uint32_t kAgentDim = 88;
  static constexpr uint32_t kBucketPose = 88;             // 7: root, position + quaternion wxyz
  static constexpr uint32_t kBucketVelocity = 95;         // 3
  static constexpr uint32_t kBucketAngularVelocity = 98;  // 3
  static constexpr uint32_t kBailJoint = 101;             // 4: q, qdot, lower, upper (0 without a bail)
  static constexpr uint32_t kBallPosition = 105;          // 3
  static constexpr uint32_t kBallVelocity = 108;          // 3
  static constexpr uint32_t kPlatformPose = 111;          // 7: centre of the box
  static constexpr uint32_t kPlatformHalfSize = 118;      // 3
  static constexpr uint32_t kBucketRim = 121;             // 4: height, outer y, inner y, outer x
  static constexpr uint32_t kDim = 125;
};

constexpr uint32_t kRobotDof = 22;
constexpr double kBallRadius = 0.05;   // m (facts)
constexpr double kDensity = 1000;      // bucket and ball, kg/m^3 (facts)
constexpr double kBucketFriction = 0.5;
const Eigen::Vector3d kPlatformHalfSize(0.3, 0.3, 0.1);

// ---- reward (C.1.3) ---------------------------------------------------------------

// What the reward reads, measured by the task each step.
struct RewardInputs {
  double gripper_distance = 1;   // mean of the four pads' distances to the bucket's surface, m
  double height_difference = 0;  // |z| of (right gripper - left gripper) in the bucket frame, m
  double opposition = 0;         // cosine distance of the two grippers seen from the rim centre, [0, 2]
  double tilt = 0;               // bucket axis from vertical, rad
  double lift = 0;               // bucket root height above its height at reset, m
  double speed = 0, angular_speed = 0;  // bucket root, m/s and rad/s
  double up_speed = 0;           // vertical velocity of the root, m/s
  double platform_distance = 1;  // root to platform centre in the plane, m
  double speed_to_platform = 0;  // horizontal velocity along the direction to the platform, m/s
  double action_norm = 0;
};

enum class RewardStage { kApproach = 1, kLift = 2, kCarry = 3, kHold = 4 };

struct RewardConstants {
  static constexpr double kNear = 0.1;           // m: grippers close enough (stage 2)
  static constexpr double kLiftHeight = 0.2;     // m: the platform's top
  static constexpr double kLiftTolerance = 0.03;
  static constexpr double kOnPlatform = 0.3;     // m, in the plane (B.4)
  static constexpr double kUpright = 0.1 * manibench::sdk::kPi;
  static constexpr double kTipped = 0.4 * manibench::sdk::kPi;
  static constexpr double kStaticSpeed = 0.1, kStaticAngularSpeed = 0.2;
};

RewardStage calcRewardStage(const RewardInputs& in);
// Four stages; every stage's rewards lie strictly above all of the stage
// before (docs/tasks/move_bucket.md has the terms and the ranges).
double calcStagedReward(const RewardInputs& in);

// ---- the task -------------------------------------------------------------------------

class MoveBucketTask : public sdk::Task {
 public:
  explicit MoveBucketTask(const Config& config);

  sdk::TaskSpec describe() const override;
  std::vector<std::string> listObjects(const std::string& split) const override;
  void buildScene(SceneView& scene, const std::string& object_id) override;
  void reset(SceneView& scene, uint64_t seed) override;
  void observe(const SceneView& scene, Eigen::Map<Eigen::VectorXd> out) override;
  double computeReward(const SceneView& scene, Eigen::Map<const Eigen::VectorXd> action) override;
  std::vector<sdk::Condition> evaluateSuccess(const SceneView& scene) override;
  // reached (the pads within the reward's kNear), holding (both grippers
  // press on the body), progress (half the lift to the platform's top, half
  // the way to it in the plane), fallen (tipped past kTipped): what the
  // survey classifies a failure by (manibench/outcome.hpp).
  std::vector<double> measureProgress(const SceneView& scene) const override;
  std::string getObjectCategory(const std::string& object_id) const override {
    return buckets_.getCategory(object_id);
  }

 private:
  RewardInputs measure(const SceneView& scene, double action_norm) const;

  std::string cache_dir_;
  // The scale of each bucket (assets/objects/move_bucket.yaml: ManiSkill
  // v1's 0.3, and its per-object exceptions; task.partnet_scale).
  ObjectFacts facts_;
  uint32_t hold_steps_;
  // the robot's facts (assets/robots/mobile_panda_dual.yaml) and state
  std::unique_ptr<mobile_panda::AgentState> robot_state_;
  ObjectCatalog<BucketModel> buckets_;
  // the scene
  std::shared_ptr<const BucketModel> bucket_;
  mb_id robot_ = -1, bucket_id_ = -1, ball_id_ = -1, platform_id_ = -1;
  mb_id body_link_ = -1, ball_link_ = -1;
  std::vector<mb_id> body_parts_;  // BucketModel::body_parts, or body_link_
  int bail_index_ = -1;             // in the bucket's joint vector
  uint32_t bucket_joint_count_ = 0;
  double initial_height_ = 0;       // root height at reset
  double initial_platform_distance_ = 1;  // root to platform centre in the plane at reset
  Eigen::Vector3d platform_centre_ = Eigen::Vector3d(0, 0, 0.1);
};

// The expert's phases, in order (an episode starts in the first).
enum class ExpertPhase { kApproach, kDescend, kSqueeze, kLift, kCarry, kLower, kRelease, kRetreat };

// Scripted expert over mobile_panda_ee (privileged state): approach, grip the
// rim from both sides, lift, carry, set down, release.
class MoveBucketExpert : public mobile_panda::Expert<ExpertPhase> {
 public:
  explicit MoveBucketExpert(const sdk::PolicyContext& context);
  void reset(uint64_t seed) override;
  Eigen::VectorXd act(const sdk::Observation& observation) override;

  struct View;     // what one step reads from the state (move_bucket_expert.cpp)
  struct Command;  // what one step commands

 private:
  using Phase = ExpertPhase;
  View read(const sdk::Observation& observation);
  // One function per phase: each sets its part of the command and says
  // when the next phase begins.
  void approach(const View& v, Command& c);
  void descend(const View& v, Command& c);
  void squeeze(const View& v, Command& c);
  void lift(const View& v, Command& c);
  void carry(const View& v, Command& c);
  void lower(const View& v, Command& c);
  void release(const View& v, Command& c);
  void retreat(const View& v, Command& c);
  Eigen::VectorXd calcAction(const View& v, const Command& c) const;

  double grip_side_ = 1;        // which way along the bucket's y the base's y points
  std::array<double, 2> finger_sign_{-1, -1};  // per arm: fingers along +-the grip axis
  double grasp_lift_ = 0;       // lift when the grippers closed
  double carry_speed_ = 0;      // m/s, ramped up and down
  Eigen::Vector2d carry_goal_ = Eigen::Vector2d::Zero();  // the base's goal while carrying (world)
  double held_yaw_ = 0;         // base yaw while holding
  uint32_t settled_steps_ = 0;
};

}  // namespace move_bucket
