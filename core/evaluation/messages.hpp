// The messages between the evaluation's coordinator and its workers, in the
// one wire format (<manibench/wire_format.hpp>: framing, Writer, Reader),
// and what packEpisodeRecord sends between MPI ranks.
#pragma once

#include <manibench/trajectory.hpp>
#include <manibench/evaluation.hpp>
#include <manibench/wire_format.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace manibench::evaluation_detail {

using wire::Reader;
using wire::Writer;

// The first byte of every payload.
enum Message : uint8_t {
  kReady = 1,       // worker -> coordinator: set up; the task as configured
  kSetupError = 2,  // worker -> coordinator: could not set up; why
  kResult = 3,      // worker -> coordinator: one episode's record
  kRun = 10,        // coordinator -> worker: run this episode
};

// The payloads after their Message byte, written (Stream = Writer, const
// records) or read (Stream = Reader) field by field.

// kReady: the task as the worker's environment configures it.
template <class Stream, class Info>
void transferReady(Stream& s, Info& info) {
  s.fields(info.observation_mode, info.controller, info.condition_names, info.split_objects,
           info.split_categories, info.max_episode_steps, info.action_dim, info.observation_dim);
}

// kRun: the episode to run.
template <class Stream, class Spec>
void transferRun(Stream& s, Spec& spec) {
  s.fields(spec.index, spec.object_id, spec.level, spec.seed);
}

// kResult: the episode's index (of its spec, which the coordinator has
// whole), then its outcome.
template <class Stream, class Record>
void transferResult(Stream& s, Record& r) {
  s.fields(r.spec.index, r.steps, r.total_reward, r.success, r.success_once, r.flags, r.failure, r.failure_step,
           r.message, r.seconds, r.sources, r.max_opened);
}

// After kResult's record: a recorded trajectory (a u8 says whether one
// follows), then a u8: whether the worker leaves after this episode.
template <class Stream, class Recorded>
void transferTrajectory(Stream& s, Recorded& t) {
  s.fields(t.object_id, t.level, t.seed, t.steps, t.success, t.total_reward, t.action_dim,
           t.condition_count, t.actions, t.policy_actions, t.rewards, t.terminated, t.truncated, t.success_flags,
           t.conditions, t.mode, t.state_dim, t.state, t.mask_count, t.point_counts, t.xyz,
           t.point_rgb, t.point_masks, t.camera_count, t.height, t.width, t.image_rgb, t.image_rgb_bytes,
           t.depth, t.image_masks, t.env_states, t.env_state_offsets);
}

}  // namespace manibench::evaluation_detail
