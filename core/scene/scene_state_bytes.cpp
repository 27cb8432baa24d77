// Scene::encodeState and decodeState: a SceneState as bytes and back.
//
// Layout (version 1, host byte order): "MBSC", version, the structure's
// fingerprint (FNV-1a of the articulations, their links and joints, the
// contact shapes and the state's sizes), time, q, u, the friction anchors,
// then per joint slot its drive command, driven/balanced flags, damping and
// friction. Everything else in a SimTK::State is fixed by the structure (or
// a cache), so a state is rebuilt from a copy of the scene's own.
#include <manibench/sdk/state.hpp>

#include <cstring>
#include <sstream>

#include "scene_impl.hpp"

namespace manibench {
namespace {

constexpr char kMagic[4] = {'M', 'B', 'S', 'C'};
constexpr uint32_t kVersion = 1;

uint64_t hashBytes(uint64_t h, const void* data, std::size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  for (std::size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}
uint64_t hashString(uint64_t h, const std::string& s) {
  h = hashBytes(h, s.data(), s.size());
  return hashBytes(h, "\0", 1);
}
uint64_t hashNumber(uint64_t h, uint64_t v) { return hashBytes(h, &v, sizeof v); }

}  // namespace

uint64_t Scene::Impl::calcStructureFingerprint() const {
  uint64_t h = 14695981039346656037ull;
  for (const Articulation& art : articulations) {
    h = hashString(h, art.name);
    for (const scene_detail::LinkModel& link : art.model.links) h = hashString(h, link.name);
    for (const JointDescription& joint : art.model.joints) h = hashString(h, joint.name);
  }
  h = hashNumber(h, uint64_t(contact_force->getNumShapes()));
  const SimTK::State& s = getState();
  h = hashNumber(h, uint64_t(s.getNQ()));
  return hashNumber(h, uint64_t(s.getNU()));
}

std::vector<std::uint8_t> Scene::encodeState(const SceneState& saved) const {
  impl_->requireFinalized("encodeState");
  if (!saved.data || saved.data->scene_id != impl_->id)
    throw SceneError("Scene::encodeState: the SceneState is not one of this scene's saveState()");
  const SimTK::State& s = saved.data->state;
  const scene_detail::JointControls& c = saved.data->controls;
  sdk::StateWriter out;
  out.writeBytes(kMagic, sizeof kMagic);
  out.write(kVersion);
  out.write(impl_->calcStructureFingerprint());
  out.write(s.getTime());
  out.write<uint32_t>(uint32_t(s.getNQ()));
  out.writeBytes(&s.getQ()[0], sizeof(double) * std::size_t(s.getNQ()));
  out.write<uint32_t>(uint32_t(s.getNU()));
  out.writeBytes(&s.getU()[0], sizeof(double) * std::size_t(s.getNU()));
  const auto& anchors = impl_->contact_force->getAnchors(s).anchors;
  out.write<uint32_t>(uint32_t(anchors.size()));
  for (const scene_detail::FrictionAnchor& a : anchors) {
    out.write(a.pair);
    out.write(a.feature);
    for (int k = 0; k < 3; ++k) out.write(a.on_a[k]);
    for (int k = 0; k < 3; ++k) out.write(a.on_b[k]);
  }
  out.write<uint32_t>(uint32_t(c.drives.size()));
  for (std::size_t j = 0; j < c.drives.size(); ++j) {
    out.writeBytes(&c.drives[j], sizeof(DriveCommand));
    out.write<uint8_t>(c.driven[j]);
    out.write<uint8_t>(c.balanced[j]);
    out.write(c.damping[j]);
    out.write(c.friction[j]);
  }
  return out.bytes();
}

SceneState Scene::decodeState(const std::uint8_t* data, std::size_t size) const {
  SceneState saved = impl_->captureState("decodeState");
  SimTK::State& s = saved.data->state;
  scene_detail::JointControls& c = saved.data->controls;
  try {
    sdk::StateReader in(data, size);
    char magic[4];
    in.readBytes(magic, sizeof magic);
    if (std::memcmp(magic, kMagic, sizeof magic) != 0)
      throw SceneError("Scene::decodeState: not a scene state (no MBSC header)");
    const uint32_t version = in.read<uint32_t>();
    if (version != kVersion)
      throw SceneError("Scene::decodeState: scene state version " + std::to_string(version) +
                       ", this build reads version " + std::to_string(kVersion));
    if (in.read<uint64_t>() != impl_->calcStructureFingerprint())
      throw SceneError(
          "Scene::decodeState: the state is of a scene of another structure (other "
          "articulations, links, joints or contact shapes: another object?)");
    s.updTime() = in.read<double>();
    if (in.read<uint32_t>() != uint32_t(s.getNQ()))
      throw SceneError("Scene::decodeState: position count differs");
    in.readBytes(&s.updQ()[0], sizeof(double) * std::size_t(s.getNQ()));
    if (in.read<uint32_t>() != uint32_t(s.getNU()))
      throw SceneError("Scene::decodeState: speed count differs");
    in.readBytes(&s.updU()[0], sizeof(double) * std::size_t(s.getNU()));
    scene_detail::FrictionAnchorSet anchors;
    anchors.anchors.resize(in.read<uint32_t>());
    for (scene_detail::FrictionAnchor& a : anchors.anchors) {
      in.read(a.pair);
      in.read(a.feature);
      for (int k = 0; k < 3; ++k) in.read(a.on_a[k]);
      for (int k = 0; k < 3; ++k) in.read(a.on_b[k]);
    }
    impl_->contact_force->setAnchors(s, std::move(anchors));
    if (in.read<uint32_t>() != uint32_t(c.drives.size()))
      throw SceneError("Scene::decodeState: joint count differs");
    for (std::size_t j = 0; j < c.drives.size(); ++j) {
      in.readBytes(&c.drives[j], sizeof(DriveCommand));
      c.driven[j] = char(in.read<uint8_t>());
      c.balanced[j] = char(in.read<uint8_t>());
      in.read(c.damping[j]);
      in.read(c.friction[j]);
    }
    if (!in.atEnd())
      throw SceneError("Scene::decodeState: " + std::to_string(in.getRemaining()) +
                       " bytes left over");
  } catch (const sdk::Error& e) {
    throw SceneError(std::string("Scene::decodeState: ") + e.what());
  }
  return saved;
}

std::string Scene::findStateDifference(const std::vector<std::uint8_t>& a,
                                       const std::vector<std::uint8_t>& b) const {
  if (a == b) return "";
  const SceneState x = decodeState(a.data(), a.size()), y = decodeState(b.data(), b.size());
  const SimTK::State& sx = x.data->state;
  const SimTK::State& sy = y.data->state;
  auto number = [](double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
  };
  auto differs = [](double p, double q) { return std::memcmp(&p, &q, sizeof p) != 0; };
  if (differs(sx.getTime(), sy.getTime()))
    return "time " + number(sx.getTime()) + " vs " + number(sy.getTime());
  for (int i = 0; i < sx.getNQ(); ++i)
    if (differs(sx.getQ()[i], sy.getQ()[i]))
      return "position q[" + std::to_string(i) + "] of " + impl_->describeMobod(impl_->q_mobod[i]) +
             ": " + number(sx.getQ()[i]) + " vs " + number(sy.getQ()[i]);
  for (int i = 0; i < sx.getNU(); ++i)
    if (differs(sx.getU()[i], sy.getU()[i]))
      return "speed u[" + std::to_string(i) + "] of " + impl_->describeMobod(impl_->u_mobod[i]) +
             ": " + number(sx.getU()[i]) + " vs " + number(sy.getU()[i]);
  const auto& ax = impl_->contact_force->getAnchors(sx).anchors;
  const auto& ay = impl_->contact_force->getAnchors(sy).anchors;
  if (ax.size() != ay.size())
    return "friction anchors: " + std::to_string(ax.size()) + " vs " + std::to_string(ay.size());
  for (std::size_t i = 0; i < ax.size(); ++i)
    if (std::memcmp(&ax[i], &ay[i], sizeof ax[i]) != 0)
      return "friction anchor " + std::to_string(i) + " (shapes " +
             std::to_string(ax[i].pair >> 32) + " and " + std::to_string(ax[i].pair & 0xFFFFFFFFu) +
             ") moved";
  const scene_detail::JointControls& cx = x.data->controls;
  const scene_detail::JointControls& cy = y.data->controls;
  for (std::size_t j = 0; j < cx.drives.size(); ++j)
    if (std::memcmp(&cx.drives[j], &cy.drives[j], sizeof(DriveCommand)) != 0 ||
        cx.driven[j] != cy.driven[j] || cx.balanced[j] != cy.balanced[j] ||
        differs(cx.damping[j], cy.damping[j]) || differs(cx.friction[j], cy.friction[j]))
      return "drive or dynamics of joint slot " + std::to_string(j) + " (" +
             impl_->describeMobod(impl_->joint_mobods[j]) + ")";
  return "the encodings differ";
}

}  // namespace manibench
