// Everything the move_bucket plugin library registers, in one place.
#include "move_bucket.hpp"

MANIBENCH_REGISTER_TASK(move_bucket::MoveBucketTask, "MoveBucket-v0",
                        "dual-arm mobile Panda carries a bucket with a ball onto a platform (ManiSkill v1)");
MANIBENCH_REGISTER_POLICY_FOR_CONTROLLER(move_bucket::MoveBucketExpert, "move_bucket_expert",
                                         "scripted expert for MoveBucket-v0 over mobile_panda_ee (privileged state)",
                                         "mobile_panda_ee");
MANIBENCH_PLUGIN_LIBRARY("manibench_move_bucket", "0.1.0");
