// The task's segmentation masks on a scene (ABI 1.1 add_to_mask): which
// visuals belong to which mask, and so which pixels.
#include <manibench/visual_observer.hpp>

namespace manibench {
namespace {

// "2 masks ('hand', 'robot')": the task's mask list, for errors.
std::string describeMasks(const std::vector<std::string>& names) {
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "'" : ", '") + n + "'";
  return std::to_string(names.size()) + " mask" + (names.size() == 1 ? "" : "s") +
         (list.empty() ? "" : " (" + list + ")");
}

}  // namespace

SegmentationMasks::SegmentationMasks(std::vector<std::string> names) : names_(std::move(names)) {
  if (names_.size() > kMaxMasks)
    throw SceneError("a task may declare at most " + std::to_string(kMaxMasks) +
                     " segmentation masks, this one declares " + std::to_string(names_.size()));
}

void SegmentationMasks::addVisuals(const Scene& scene, uint32_t mask, int articulation, int link,
                                   const std::string& part) {
  if (mask >= names_.size())
    throw SceneError("add_to_mask: mask index " + std::to_string(mask) +
                     " out of range: the task declares " + describeMasks(names_));
  if (articulation < 0 || articulation >= scene.getArticulationCount())
    throw SceneError("add_to_mask: no articulation with id " + std::to_string(articulation));
  const std::string& articulation_name = scene.getArticulationName(articulation);
  // Link ids are global; a link belongs to `articulation` when its name
  // finds it there.
  auto belongs = [&](int l) { return scene.findLink(articulation, scene.getLinkName(l)) == l; };
  if (link >= 0 && !belongs(link))
    throw SceneError("add_to_mask: link id " + std::to_string(link) +
                     " is not a link of articulation '" + articulation_name + "'");
  const std::vector<VisualShape>& visuals = scene.getVisualShapes();
  visual_masks_.resize(visuals.size(), 0);
  std::size_t matched = 0;
  for (std::size_t v = 0; v < visuals.size(); ++v) {
    const VisualShape& shape = visuals[v];
    if (shape.link < 0) continue;
    if (link >= 0 ? shape.link != link : !belongs(shape.link)) continue;
    if (!part.empty() && shape.name.find(part) == std::string::npos) continue;
    visual_masks_[v] |= std::uint64_t(1) << mask;
    ++matched;
  }
  if (matched == 0)
    throw SceneError(
        "add_to_mask: mask '" + names_[mask] + "': " +
        (link >= 0 ? "link '" + scene.getLinkName(link) + "' of articulation '" +
                         articulation_name + "' has no visual" +
                         (part.empty() ? "" : " whose name contains '" + part + "'")
                   : "articulation '" + articulation_name + "' has no visuals"));
}

std::uint64_t SegmentationMasks::calcPixelMasks(const CameraImages& image, std::size_t pixel) const {
  const int v = image.visual[pixel];
  return v >= 0 && std::size_t(v) < visual_masks_.size() ? visual_masks_[std::size_t(v)] : 0;
}

}  // namespace manibench
