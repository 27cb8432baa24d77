/*
 * manibench plugin ABI: the only thing that crosses the boundary between the
 * host (core + apps) and a plugin library (tasks, controllers, policies).
 *
 * Rules (see README.md, "Writing a plugin"):
 *  - Plain C: no C++ types, Eigen, exceptions or STL containers cross it.
 *  - Every growable struct starts with `struct_size`. Structs only grow at
 *    the end; a reader touches a field only if the field lies below the
 *    struct_size the writer set (MB_HAS_FIELD).
 *  - Output structs (mb_task_info, mb_controller_info, ...) are allocated by
 *    the caller, who sets struct_size to the size it knows; the callee fills
 *    only the fields that fit.
 *  - Frozen records (mb_pose, mb_segment, mb_joint_info, mb_drive_command)
 *    never change within a major version; new data goes into new records.
 *  - Every call that can fail returns mb_status and takes a caller-owned
 *    mb_error buffer; the callee writes a NUL-terminated message that fits.
 *  - Strings and arrays a plugin returns stay valid as long as the handle
 *    they came from (or, for descriptors and manifests, for the life of the
 *    process: libraries are never unloaded).
 *  - A minor version adds functions or fields at the end of structs, new
 *    flag bits, new kinds. A major version is anything else.
 *
 * The per-step contract: the order in which the host calls a task (T), its
 * controller (C) and a policy (P). Plugins may rely on it and need not
 * guard against other orders.
 *  - T build_scene once per scene, before anything else on that scene; the
 *    scene API's add_* and add_to_mask work only then.
 *  - An episode starts with T reset, then C reset, then T observe (the
 *    first observation); then P reset (ABI 1.5: P reset_episode instead,
 *    where the policy has it). The scene API's setters work only in the
 *    two resets.
 *  - Each environment step: P act on the last observation; frame_skip times
 *    C compute followed by one control tick of physics; T compute_reward;
 *    T evaluate_success exactly once; T observe. A step never comes before
 *    its episode's resets, and a failed call ends the episode.
 *  - ABI 1.2, state: between steps the host may call T get_state and
 *    C get_state. To restore an episode it resets it from the episode's
 *    seed (T reset, C reset, so that everything a reset chose is chosen
 *    again), sets the scene's state, then calls T set_state and C
 *    set_state with the bytes they gave, then T observe. A plugin's state
 *    is what changes during an episode outside the scene (filters,
 *    integrators, counters); bytes it did not write are an error it
 *    reports.
 *
 * Entry point: a plugin library exports one data symbol named
 * MB_ENTRY_POINT_NAME ("manibench_plugin_entry") of type `const void*`
 * holding the address of an `mb_entry_fn`. Boost.DLL's BOOST_DLL_ALIAS makes
 * exactly that; the C++ SDK's MANIBENCH_PLUGIN_LIBRARY macro uses it.
 */
#ifndef MANIBENCH_ABI_H
#define MANIBENCH_ABI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MB_ABI_MAJOR 1
#define MB_ABI_MINOR 8
#define MB_ENTRY_POINT_NAME "manibench_plugin_entry"

/* True when `field` of struct type `type` lies within `size` bytes. */
#define MB_HAS_FIELD(type, field, size) \
  (offsetof(type, field) + sizeof(((type*)0)->field) <= (size_t)(size))

/* ---- status and errors ------------------------------------------------ */

typedef int32_t mb_status;
#define MB_OK 0
#define MB_ERROR 1            /* generic failure; message in the buffer */
#define MB_INVALID_ARGUMENT 2 /* bad input from the caller */
#define MB_NOT_FOUND 3        /* unknown name or id */
#define MB_UNSUPPORTED 4      /* valid request this side cannot serve */
#define MB_DIVERGED 5         /* the simulation produced NaN or blew up */

/* Caller-owned message buffer. A callee writes at most `capacity` bytes,
 * always NUL-terminated when capacity > 0. */
typedef struct mb_error {
  char* message;
  size_t capacity;
} mb_error;

/* ---- shared records (frozen within a major version) ------------------- */

typedef int32_t mb_id; /* articulation or link id; negative = none */

typedef struct mb_pose {
  double position[3];
  double quaternion[4]; /* w, x, y, z; unit length */
} mb_pose;

/* A named slice [offset, offset + size) of a flat vector. */
typedef struct mb_segment {
  const char* name;
  uint32_t offset;
  uint32_t size;
  const char* description;
} mb_segment;

#define MB_JOINT_REVOLUTE 1
#define MB_JOINT_CONTINUOUS 2
#define MB_JOINT_PRISMATIC 3

/* One movable, single-degree-of-freedom joint of an articulation. Fixed
 * joints are merged into their parent and floating roots are reached through
 * the root pose, so neither appears in joint lists. */
typedef struct mb_joint_info {
  const char* name;
  uint32_t type;         /* MB_JOINT_* */
  uint32_t index;        /* position in the articulation's joint vector */
  double lower, upper;   /* limits; -inf/+inf when unlimited */
  double velocity_limit; /* rad/s or m/s; 0 when unknown */
  double effort_limit;   /* N m or N; 0 when unlimited */
} mb_joint_info;

/* In C++, fields of mb_drive_command start at 0 (a default member
 * initializer changes neither the layout nor the C view), so that a command
 * declared without an initializer is the passive "no drive" command. */
#ifdef __cplusplus
#define MB_ZERO_BY_DEFAULT = 0
#else
#define MB_ZERO_BY_DEFAULT
#endif

/* What a controller asks of one joint's drive for the next control step.
 * The host applies, at every physics evaluation,
 *   tau = stiffness (position_target - q) + damping (velocity_target - qdot)
 *         + force
 * clamped to the joint's effort limit when one is set. */
typedef struct mb_drive_command {
  double position_target MB_ZERO_BY_DEFAULT;
  double velocity_target MB_ZERO_BY_DEFAULT;
  double stiffness MB_ZERO_BY_DEFAULT;
  double damping MB_ZERO_BY_DEFAULT;
  double force MB_ZERO_BY_DEFAULT;
} mb_drive_command;

/* ---- host scene API (the host implements it, plugins call it) --------- */

typedef struct mb_scene mb_scene; /* opaque, owned by the host */

typedef struct mb_scene_api {
  uint32_t struct_size;
  uint16_t abi_major;
  uint16_t abi_minor;

  /* Building: only valid while the host runs a task's build_scene. */
  mb_status (*add_ground)(mb_scene* scene, double height, mb_error* err);
  /* Loads a URDF file; `name` must be unique in the scene. A fixed base
   * welds the root link to the world at `root`; otherwise it floats. */
  mb_status (*add_urdf_file)(mb_scene* scene, const char* path,
                             const char* name, const mb_pose* root,
                             int32_t fixed_base, mb_id* out_articulation,
                             mb_error* err);
  /* Same from text; relative mesh paths resolve against `base_dir`. */
  mb_status (*add_urdf_string)(mb_scene* scene, const char* urdf_xml,
                               const char* base_dir, const char* name,
                               const mb_pose* root, int32_t fixed_base,
                               mb_id* out_articulation, mb_error* err);

  /* Lookup. */
  mb_status (*find_articulation)(mb_scene* scene, const char* name,
                                 mb_id* out, mb_error* err);
  mb_status (*find_link)(mb_scene* scene, mb_id articulation,
                         const char* link_name, mb_id* out_link,
                         mb_error* err);
  mb_status (*get_joint_count)(mb_scene* scene, mb_id articulation,
                               uint32_t* out_count, mb_error* err);
  /* `out` is a frozen record; its name stays valid as long as the scene. */
  mb_status (*get_joint_info)(mb_scene* scene, mb_id articulation,
                              uint32_t joint_index, mb_joint_info* out,
                              mb_error* err);
  mb_status (*find_joint)(mb_scene* scene, mb_id articulation,
                          const char* joint_name, uint32_t* out_index,
                          mb_error* err);

  /* State queries; `count` must equal the articulation's joint count. */
  mb_status (*get_time)(mb_scene* scene, double* out_seconds, mb_error* err);
  mb_status (*get_joint_positions)(mb_scene* scene, mb_id articulation,
                                   double* out, uint32_t count, mb_error* err);
  mb_status (*get_joint_velocities)(mb_scene* scene, mb_id articulation,
                                    double* out, uint32_t count,
                                    mb_error* err);
  mb_status (*get_root_pose)(mb_scene* scene, mb_id articulation,
                             mb_pose* out, mb_error* err);
  mb_status (*get_link_pose)(mb_scene* scene, mb_id link, mb_pose* out,
                             mb_error* err);
  /* World-frame twist of the link frame origin: angular[3], then linear[3]. */
  mb_status (*get_link_twist)(mb_scene* scene, mb_id link, double out[6],
                              mb_error* err);
  /* Total contact force on link_a from link_b (world frame, N); link_b < 0
   * means from anything. */
  mb_status (*get_contact_force)(mb_scene* scene, mb_id link_a, mb_id link_b,
                                 double out[3], mb_error* err);

  /* State setters: valid in a task's reset (and by the host). */
  mb_status (*set_joint_positions)(mb_scene* scene, mb_id articulation,
                                   const double* q, uint32_t count,
                                   mb_error* err);
  mb_status (*set_joint_velocities)(mb_scene* scene, mb_id articulation,
                                    const double* qdot, uint32_t count,
                                    mb_error* err);
  mb_status (*set_root_pose)(mb_scene* scene, mb_id articulation,
                             const mb_pose* pose, mb_error* err);
  /* Passive joint dynamics (B.2 randomizes them per episode): viscous
   * damping (N m s/rad or N s/m) and Coulomb friction (N m or N). */
  mb_status (*set_joint_dynamics)(mb_scene* scene, mb_id articulation,
                                  uint32_t joint_index, double damping,
                                  double friction, mb_error* err);

  /* ---- ABI 1.1 ------------------------------------------------------- */

  /* Geometric Jacobian of a point fixed on `link` (`point_in_link`, in the
   * link frame) with respect to the joint velocities of `articulation`:
   * 6 rows (angular velocity x, y, z of the link, then linear velocity
   * x, y, z of the point; world frame) by `count` columns, row-major, `count`
   * being the articulation's joint count. Columns of joints that do not
   * move the link are zero. Valid whenever the state is. */
  mb_status (*calc_link_jacobian)(mb_scene* scene, mb_id articulation,
                                  mb_id link, const double point_in_link[3],
                                  double* out, uint32_t count, mb_error* err);
  /* Segmentation masks (mb_task_info.masks): the visuals of `link` whose
   * <visual name> contains `visual_name_part` (every visual of the link when
   * NULL or "") belong to mask `mask_index`. With link < 0, every visual of
   * `articulation` belongs to it. A visual may belong to several masks.
   * Only while the task builds its scene. */
  mb_status (*add_to_mask)(mb_scene* scene, uint32_t mask_index,
                           mb_id articulation, mb_id link,
                           const char* visual_name_part, mb_error* err);

  /* ---- ABI 1.3 ------------------------------------------------------- */

  /* The link id of `articulation`'s root link (its URDF's root, whose pose
   * get_root_pose reports), for get_link_pose / get_link_twist without
   * knowing the URDF's link names. */
  mb_status (*get_root_link)(mb_scene* scene, mb_id articulation,
                             mb_id* out_link, mb_error* err);
  /* A floating root's twist: angular velocity x, y, z, then the root link
   * origin's linear velocity x, y, z, world frame (get_link_twist's
   * layout). An error for a fixed base. Not while the host steps. */
  mb_status (*set_root_twist)(mb_scene* scene, mb_id articulation,
                              const double twist[6], mb_error* err);
} mb_scene_api;

/* ---- descriptors ------------------------------------------------------ */

#define MB_KIND_TASK 1u
#define MB_KIND_CONTROLLER 2u
#define MB_KIND_POLICY 3u

/* Every descriptor starts with this header; struct_size is the size of the
 * whole kind-specific descriptor. */
typedef struct mb_descriptor {
  uint32_t struct_size;
  uint32_t kind; /* MB_KIND_* */
  const char* name;
  const char* summary;
} mb_descriptor;

typedef struct mb_manifest {
  uint32_t struct_size;
  uint16_t abi_major;
  uint16_t abi_minor;
  const char* library_name;
  const char* library_version;
  uint32_t descriptor_count;
  const mb_descriptor* const* descriptors;
} mb_manifest;

typedef const mb_manifest* (*mb_entry_fn)(void);

/* ---- task ------------------------------------------------------------- */

typedef struct mb_task mb_task; /* opaque, owned by the plugin */

typedef struct mb_task_info {
  uint32_t struct_size;
  uint32_t observation_dim; /* the `state` observation vector */
  uint32_t observation_segment_count;
  const mb_segment* observation_segments;
  uint32_t success_condition_count; /* named conditions; `success` is last */
  const char* const* success_conditions;
  uint32_t mask_count; /* segmentation masks, in observation order */
  const char* const* masks;
  const char* robot_articulation; /* name given to add_urdf_* */
  uint32_t actuated_joint_count;  /* joints the controller drives, in order */
  const char* const* actuated_joints;
  const char* default_controller; /* controller name */
  const char* controller_config;  /* YAML for it; may be NULL */
  double control_frequency;       /* Hz */
  uint32_t frame_skip;            /* control steps per environment step */
  uint32_t max_episode_steps;
  /* The task's layer of the YAML configuration (physics, cameras, ...),
   * between the built-in defaults and the user's file; may be NULL. */
  const char* default_config;

  /* ---- ABI 1.1 ------------------------------------------------------- */
  /* The first agent_state_dim values of the state observation (whole
   * segments) are the robot's own state: in the pointcloud and rgbd modes
   * the policy gets only these, as ManiSkill's visual modes give only the
   * agent's state. 0: the whole vector. */
  uint32_t agent_state_dim;

  /* ---- ABI 1.6: progress signals (optional; 0 / NULL: none) ----------- */
  /* Named values that say how far an episode has come, read by the host
   * through measure_progress to tell why an episode failed (`manibench
   * survey`, docs/partnet.md "Surveying a folder"). The names the host
   * understands (others are recorded, not interpreted):
   *   "reached"  1 when the robot's effector is at the part it must act on
   *              (a handle, a chair's back, a bucket's rim), by the task's
   *              own distance; else 0
   *   "holding"  1 while the gripper holds that part (both fingers touch it)
   *   "progress" the fraction of what success needs (an opened fraction over
   *              the target's, a distance covered): 1 at the goal, below 0
   *              when the object moved the wrong way
   *   "blocked"  1 while the robot touches the object elsewhere than by
   *              the fingers (an arm on a table top, a base on a door)
   *   "fallen"   1 while the object lies knocked over (past the task's
   *              upright limit)
   *   "opened"   the fraction of the target joint's range it is open
   *              (doors, drawers): the evaluation's opening curve, read
   *              after the reset and every step (docs/evaluation.md) */
  uint32_t progress_signal_count;
  const char* const* progress_signals;
} mb_task_info;

typedef struct mb_task_descriptor {
  mb_descriptor header;
  /* config_yaml: the task's configuration as YAML text (may be empty). */
  mb_status (*create)(const char* config_yaml, mb_task** out, mb_error* err);
  void (*destroy)(mb_task* task);
  mb_status (*get_info)(mb_task* task, mb_task_info* out, mb_error* err);
  /* Object ids of a split ("train" or "test"). */
  mb_status (*list_objects)(mb_task* task, const char* split,
                            const char* const** out_ids, uint32_t* out_count,
                            mb_error* err);
  /* Adds the robot and `object_id` to an empty scene. */
  mb_status (*build_scene)(mb_task* task, const mb_scene_api* api,
                           mb_scene* scene, const char* object_id,
                           mb_error* err);
  /* Starts an episode: sets initial states and randomizes from `seed`. */
  mb_status (*reset)(mb_task* task, const mb_scene_api* api, mb_scene* scene,
                     uint64_t seed, mb_error* err);
  mb_status (*observe)(mb_task* task, const mb_scene_api* api,
                       mb_scene* scene, double* out, uint32_t dim,
                       mb_error* err);
  /* Called once per environment step, after physics (see the per-step
   * contract at the top). */
  mb_status (*compute_reward)(mb_task* task, const mb_scene_api* api,
                              mb_scene* scene, const double* action,
                              uint32_t action_dim, double* out_reward,
                              mb_error* err);
  /* One flag and one value per success condition. Called exactly once per
   * environment step, after compute_reward and before observe, so a task
   * may count steps here (the C++ SDK's TaskSpec::success_hold_steps does). */
  mb_status (*evaluate_success)(mb_task* task, const mb_scene_api* api,
                                mb_scene* scene, uint8_t* out_flags,
                                double* out_values, uint32_t count,
                                mb_error* err);

  /* ---- ABI 1.2: episode state (see the contract above) ----------------- */
  /* Writes the task's state into `out` if it fits in `capacity` bytes, and
   * its size into *out_size either way (out may be NULL to ask the size). */
  mb_status (*get_state)(mb_task* task, uint8_t* out, uint64_t capacity,
                         uint64_t* out_size, mb_error* err);
  mb_status (*set_state)(mb_task* task, const uint8_t* data, uint64_t size,
                         mb_error* err);

  /* ---- ABI 1.6: optional (NULL, or beyond struct_size in an older
   * plugin: no progress signals) ----------------------------------------- */
  /* One value per mb_task_info.progress_signals, of the scene as it is. It
   * reads the scene and changes nothing, so the host may call it at any
   * point between steps (the survey does after each). */
  mb_status (*measure_progress)(mb_task* task, const mb_scene_api* api,
                                mb_scene* scene, double* out, uint32_t count,
                                mb_error* err);

  /* ---- ABI 1.8: optional (NULL, or beyond struct_size in an older
   * plugin: no categories) ----------------------------------------------- */
  /* The category of an object of list_objects, for the evaluation's rates
   * per category (a PartNet-Mobility object's is its folder's name, e.g.
   * "StorageFurniture"); "" when it has none (a generated object). The text
   * stays valid while the task lives. */
  mb_status (*get_object_category)(mb_task* task, const char* object_id,
                                   const char** out_category, mb_error* err);
} mb_task_descriptor;

/* ---- controller ------------------------------------------------------- */

typedef struct mb_controller mb_controller; /* opaque, owned by the plugin */

/* Handed to a controller at creation: which joints it drives. */
typedef struct mb_controller_context {
  uint32_t struct_size;
  mb_id articulation;
  uint32_t joint_count;
  const mb_joint_info* joints; /* actuated joints, in action order */
  double control_frequency;    /* Hz */
} mb_controller_context;

/* The host cancels gravity and Coriolis forces of the driven joints by
 * inverse dynamics at every physics evaluation (supplement B.7). */
#define MB_CONTROLLER_BALANCE_PASSIVE_FORCES (1u << 0)

typedef struct mb_controller_info {
  uint32_t struct_size;
  uint32_t action_dim;
  uint32_t action_segment_count;
  const mb_segment* action_segments;
  uint32_t flags; /* MB_CONTROLLER_* */

  /* ---- ABI 1.7 (beyond struct_size, or NULL: no layer) ----------------- */
  /* The controller this one is a layer over: its compute ends in that
   * controller's path, so that the action get_base_action reports after a
   * compute makes the base controller (same configuration) compute the
   * same drive commands, bit for bit (`demos convert --controller`). */
  const char* base_controller;
} mb_controller_info;

typedef struct mb_controller_descriptor {
  mb_descriptor header;
  mb_status (*create)(const char* config_yaml,
                      const mb_controller_context* context,
                      mb_controller** out, mb_error* err);
  void (*destroy)(mb_controller* controller);
  mb_status (*get_info)(mb_controller* controller, mb_controller_info* out,
                        mb_error* err);
  mb_status (*reset)(mb_controller* controller, const mb_scene_api* api,
                     mb_scene* scene, mb_error* err);
  /* One control step: a normalized action in [-1, 1] (already validated and
   * clipped by the host) to one drive command per joint. Always after the
   * episode's reset. */
  mb_status (*compute)(mb_controller* controller, const mb_scene_api* api,
                       mb_scene* scene, const double* action,
                       uint32_t action_dim, mb_drive_command* out,
                       uint32_t joint_count, mb_error* err);

  /* ---- ABI 1.2: episode state, as the task's ------------------------- */
  mb_status (*get_state)(mb_controller* controller, uint8_t* out,
                         uint64_t capacity, uint64_t* out_size, mb_error* err);
  mb_status (*set_state)(mb_controller* controller, const uint8_t* data,
                         uint64_t size, mb_error* err);

  /* ---- ABI 1.7: optional (NULL, or beyond struct_size in an older
   * plugin: no layer) ---------------------------------------------------- */
  /* After a compute, the normalized action of mb_controller_info's
   * base_controller that computes the same drive commands from the same
   * state (`dim` its action size). MB_UNSUPPORTED from a controller that is
   * no layer, or before its first compute. */
  mb_status (*get_base_action)(mb_controller* controller, double* out,
                               uint32_t dim, mb_error* err);
} mb_controller_descriptor;

/* ---- policy ----------------------------------------------------------- */

typedef struct mb_policy mb_policy; /* opaque, owned by the plugin */

typedef struct mb_policy_context {
  uint32_t struct_size;
  const char* task_name;
  const char* observation_mode; /* "state", "pointcloud", "rgbd" */
  uint32_t observation_dim;
  uint32_t observation_segment_count;
  const mb_segment* observation_segments;
  uint32_t action_dim;
  uint32_t action_segment_count;
  const mb_segment* action_segments;
} mb_policy_context;

/* One observation; grows with the visual modes. */
typedef struct mb_observation {
  uint32_t struct_size;
  const double* state;
  uint32_t state_dim;
  uint32_t step; /* environment step within the episode, from 0 */

  /* ---- ABI 1.1: visual modes (zero / NULL in the modes that lack them).
   * mask_count equals mb_task_info.mask_count. */
  uint32_t mask_count;
  /* "pointcloud": world-frame points after the subsampling of supplement
   * D.1, row-major: xyz and rgb (in [0, 1]) point_count x 3, masks
   * point_count x mask_count (0 or 1). */
  uint32_t point_count;
  const float* points_xyz;
  const float* points_rgb;
  const uint8_t* points_mask;
  /* "rgbd": every camera's image, cameras stacked along the channel axis as
   * ManiSkill does, row-major height x width x channels: rgb (3 per camera,
   * in [0, 1]), depth (1 per camera, metres along the optical axis; 0 where
   * nothing was hit), masks (mask_count per camera, 0 or 1). */
  uint32_t camera_count;
  uint32_t image_height;
  uint32_t image_width;
  const float* image_rgb;
  const float* image_depth;
  const uint8_t* image_masks;
} mb_observation;

/* ABI 1.5: the episode a policy starts, for reset_episode. A policy made
 * of one agent per object (supplement C.2's demonstration agents) picks its
 * agent by object_id. Strings are empty where the host does not know
 * them; they stay valid during the call only. */
typedef struct mb_episode_info {
  uint32_t struct_size;
  const char* task_name; /* the registered task's, also for a fixed-object id */
  const char* object_id;
  uint64_t seed; /* as reset's */
} mb_episode_info;

typedef struct mb_policy_descriptor {
  mb_descriptor header;
  mb_status (*create)(const char* config_yaml,
                      const mb_policy_context* context, mb_policy** out,
                      mb_error* err);
  void (*destroy)(mb_policy* policy);
  mb_status (*reset)(mb_policy* policy, uint64_t seed, mb_error* err);
  mb_status (*act)(mb_policy* policy, const mb_observation* observation,
                   double* out_action, uint32_t action_dim, mb_error* err);

  /* ---- ABI 1.4 ------------------------------------------------------- */
  /* The controller whose actions the policy outputs (a controller's name,
   * e.g. a scripted expert's "mobile_panda_ee"), or NULL / "" for a policy
   * that acts through whatever controller the task configures. A host runs
   * the policy on it when the user names no controller, and refuses a
   * different one the user names. */
  const char* controller;

  /* ---- ABI 1.5: optional (NULL, or beyond struct_size in an older
   * plugin: the host calls reset). When set, the host calls it instead of
   * reset at each episode's start. */
  mb_status (*reset_episode)(mb_policy* policy, const mb_episode_info* episode,
                             mb_error* err);
} mb_policy_descriptor;

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* MANIBENCH_ABI_H */
