// The generated buckets' mesh files on disk: URDF names its convex pieces
// by file, so a generated bucket's OBJ texts are written once into a cache
// folder named after the bucket and a hash of the texts (the kit's
// writeFilesOnce: parallel workers agree on one folder).
#include "move_bucket.hpp"

#include <manibench/kit/file_cache.hpp>

#include <filesystem>

namespace move_bucket {

void writeMeshFiles(BucketModel& model, const std::string& cache_root) {
  if (model.files.empty()) return;
  ContentHash hash;
  for (const auto& [name, text] : model.files) hash.add(name).add(text);
  const std::string folder = (std::filesystem::path(cache_root) / "buckets" / (model.id + "-" + hash.str())).string();
  writeFilesOnce(folder, model.files, "MoveBucket");
  model.base_dir = folder;
}

}  // namespace move_bucket
