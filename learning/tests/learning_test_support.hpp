// What the learning module's training tests share.
#pragma once

#include <manibench/learning/checkpoint.hpp>

#include <string>

namespace manibench::learning {

// Every parameter and buffer of every network of two checkpoints, bit for bit.
inline bool sameWeights(const std::string& a, const std::string& b) {
  const LoadedCheckpoint x = loadCheckpoint(a, torch::kCPU, false), y = loadCheckpoint(b, torch::kCPU, false);
  const auto& nx = x.algorithm->getNetworks();
  const auto& ny = y.algorithm->getNetworks();
  if (nx.size() != ny.size()) return false;
  for (std::size_t i = 0; i < nx.size(); ++i) {
    const auto px = nx[i].second->named_parameters(), py = ny[i].second->named_parameters();
    for (const auto& p : px)
      if (!torch::equal(p.value(), py[p.key()])) return false;
    const auto bx = nx[i].second->named_buffers(), by = ny[i].second->named_buffers();
    for (const auto& p : bx)
      if (!torch::equal(p.value(), by[p.key()])) return false;
  }
  return true;
}

}  // namespace manibench::learning
