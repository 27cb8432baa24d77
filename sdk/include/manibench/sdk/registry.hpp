// The per-library descriptor table and the entry point that publishes it.
#pragma once

#include <manibench/abi.h>
#include <manibench/sdk/common.hpp>

#include <boost/dll/alias.hpp>

#include <vector>

#define MANIBENCH_SDK_CONCAT_INNER(a, b) a##b
#define MANIBENCH_SDK_CONCAT(a, b) MANIBENCH_SDK_CONCAT_INNER(a, b)

namespace manibench::sdk::detail {

// Filled by the registration macros during the library's static
// initialization, read by the entry point after dlopen has returned.
MANIBENCH_SDK_HIDDEN inline std::vector<const mb_descriptor*>& registeredDescriptors() {
  static std::vector<const mb_descriptor*> descriptors;
  return descriptors;
}

MANIBENCH_SDK_HIDDEN inline const mb_manifest* buildManifest(const char* library_name,
                                                            const char* library_version) {
  static const mb_manifest manifest = [&] {
    mb_manifest m{};
    m.struct_size = sizeof(mb_manifest);
    m.abi_major = MB_ABI_MAJOR;
    m.abi_minor = MB_ABI_MINOR;
    m.library_name = library_name;
    m.library_version = library_version;
    m.descriptor_count = static_cast<uint32_t>(registeredDescriptors().size());
    m.descriptors = registeredDescriptors().data();
    return m;
  }();
  return &manifest;
}

// Descriptors live for the life of the process (libraries are never
// unloaded), so they are allocated once and never freed.
template <class Descriptor>
Descriptor* newDescriptor(uint32_t kind, const char* name, const char* summary) {
  auto* d = new Descriptor{};
  d->header.struct_size = sizeof(Descriptor);
  d->header.kind = kind;
  d->header.name = name;
  d->header.summary = summary;
  registeredDescriptors().push_back(&d->header);
  return d;
}

}  // namespace manibench::sdk::detail

// Exactly once per plugin library, in any one of its source files:
//   MANIBENCH_PLUGIN_LIBRARY("my_tasks", "1.2.0");
// Exports the entry point the host looks for (MB_ENTRY_POINT_NAME).
#define MANIBENCH_PLUGIN_LIBRARY(library_name, library_version)          \
  namespace manibench_plugin_library {                                   \
  static const mb_manifest* manifest() {                                 \
    return ::manibench::sdk::detail::buildManifest(library_name,         \
                                                   library_version);     \
  }                                                                      \
  }                                                                      \
  BOOST_DLL_ALIAS(manibench_plugin_library::manifest, manibench_plugin_entry)
