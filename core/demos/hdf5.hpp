// A thin C++ layer over libhdf5's C API for the demonstration files: owned
// handles, errors as exceptions carrying HDF5's own reasons, and typed
// datasets and attributes. Only what demos need.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace manibench::demos_detail {

// An HDF5 call failed; the message names the file, the object and HDF5's
// reason.
class Hdf5Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An owned hid_t of any kind, closed with the function its kind needs.
class Handle {
 public:
  Handle() = default;
  explicit Handle(hid_t id) : id_(id) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : id_(o.id_) { o.id_ = H5I_INVALID_HID; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      o.id_ = H5I_INVALID_HID;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  void reset();

 private:
  hid_t id_ = H5I_INVALID_HID;
};

// HDF5's error stack as one line ("H5Dopen2: ... ; ..."), then cleared.
std::string takeErrorStack();
// Throws Hdf5Error("<what>: <HDF5's reason>") when `id` is negative.
hid_t check(hid_t id, const std::string& what);
void check(herr_t status, const std::string& what);

// Files. create: new (truncating) with the latest format and a root group
// index laid out so that a file cut short keeps the trajectories written
// before the cut (demo_file.cpp says why), its header sized for
// `root_links` links. openForReading skips HDF5's end-of-file check, so
// that such a file still opens.
Handle createFile(const std::string& path, unsigned root_links);
Handle openForReading(const std::string& path);
void flushFile(const Handle& file);

// What a file's superblock (format version 2 or 3, as createFile writes)
// and its root group's first header chunk say about where things lie, read
// with plain file reads, so that a file HDF5 refuses can still be
// described. Fields are 0 where the file is too short or of another format.
struct FileLayout {
  uint64_t bytes = 0;            // the file's size on disk
  uint64_t superblock_end = 0;   // the superblock's size (48 with 8-byte offsets)
  uint64_t recorded_bytes = 0;   // the end of file the superblock records
  uint64_t root_header = 0;      // the root group's object header
  uint64_t root_header_end = 0;  // the end of its first chunk
  // Shorter than the superblock records: cut short (or still being written).
  bool isCutShort() const { return recorded_bytes > bytes; }
};
FileLayout readFileLayout(const std::string& path);

// The end (byte offset) of the last byte of a dataset's data in the file:
// every chunk of a chunked dataset, the block of a contiguous one; 0 when
// it has none (empty, or compact: inside its header).
uint64_t calcDataEnd(const Handle& parent, const std::string& name);

// Groups: created with room for `links` links in their header.
Handle createGroup(const Handle& parent, const std::string& name, unsigned links);
Handle openGroup(const Handle& parent, const std::string& name);
bool hasLink(const Handle& parent, const std::string& name);
// Whether the group keeps its links in HDF5's dense storage (a fractal heap
// and a B-tree outside its header), as files before 2026-11-26 did.
bool hasDenseLinks(const Handle& group);
// The names of a group's links, in creation order where tracked, else by name.
std::vector<std::string> listLinks(const Handle& group);

// Element types of the datasets and attributes demos write.
template <class T>
hid_t getMemoryType();

// A chunked dataset of `dims` (row-major) holding `data` (size = product of
// dims), deflate-compressed, one chunk per `rows_per_chunk` rows (all other
// dimensions whole); `data` may be empty for a dimension of 0.
template <class T>
void writeDataset(const Handle& parent, const std::string& name, const std::vector<hsize_t>& dims,
                  const T* data, hsize_t rows_per_chunk = 0);
template <class T>
void writeDataset(const Handle& parent, const std::string& name, const std::vector<hsize_t>& dims,
                  const std::vector<T>& data, hsize_t rows_per_chunk = 0) {
  writeDataset(parent, name, dims, data.data(), rows_per_chunk);
}
// The dataset's dims; its data converted to T (HDF5 converts integer and
// float types); throws when the element class differs from T's.
std::vector<hsize_t> readDims(const Handle& parent, const std::string& name);
template <class T>
std::vector<T> readDataset(const Handle& parent, const std::string& name,
                           std::vector<hsize_t>* dims = nullptr);
// The dataset's element size in bytes and whether it is a float type.
struct ElementType {
  std::size_t size = 0;
  bool is_float = false;
};
ElementType readElementType(const Handle& parent, const std::string& name);

// Attributes: strings (UTF-8, variable length), unsigned integers, doubles.
void writeAttribute(const Handle& object, const std::string& name, const std::string& value);
void writeAttribute(const Handle& object, const std::string& name, uint64_t value);
void writeAttribute(const Handle& object, const std::string& name, double value);
void writeAttribute(const Handle& object, const std::string& name,
                    const std::vector<std::string>& values);
bool hasAttribute(const Handle& object, const std::string& name);
std::string readStringAttribute(const Handle& object, const std::string& name);
uint64_t readUintAttribute(const Handle& object, const std::string& name);
double readDoubleAttribute(const Handle& object, const std::string& name);
std::vector<std::string> readStringsAttribute(const Handle& object, const std::string& name);

}  // namespace manibench::demos_detail
