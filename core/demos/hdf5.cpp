#include "hdf5.hpp"

#include <algorithm>
#include <fstream>
#include <mutex>
#include <vector>

namespace manibench::demos_detail {
namespace {

// HDF5 prints its error stack to stderr by default; here errors become
// exceptions with the stack as their reason.
//
// Nor does HDF5 close what is open at exit: a file whose close failed (its
// last flush met a full disk) stays in HDF5's list half closed, and the
// library's atexit clean-up then segfaulted closing it again (HDF5 1.10.8),
// after the command had printed its error. Every file here is closed by
// its Handle; one whose close failed has lost its unflushed tail anyway.
// H5dont_atexit counts only before HDF5's first call: this is every
// entry point's first (createFile, openForReading).
void silenceHdf5() {
  static std::once_flag once;
  std::call_once(once, [] {
    H5dont_atexit();
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  });
}

// The outermost few entries say what failed; the innermost says why (the
// system call's errno: "No space left on device", "Not a directory").
herr_t collectError(unsigned, const H5E_error2_t* e, void* data) {
  auto* entries = static_cast<std::vector<std::string>*>(data);
  std::string desc = e->desc ? e->desc : "?";
  // The low-level driver's entries start with the time of day and a line
  // break ("time = Sun Dec  6 22:13:27 2026\n, name = ..."): one line, no time.
  const std::size_t time = desc.find("time = "), end = desc.find("\n, ", time);
  if (time != std::string::npos && end != std::string::npos) desc.erase(time, end + 3 - time);
  std::replace(desc.begin(), desc.end(), '\n', ' ');
  entries->push_back(std::string(e->func_name ? e->func_name : "?") + ": " + desc);
  return 0;
}

Handle createTypedProperties(hid_t cls) { return Handle(check(H5Pcreate(cls), "H5Pcreate")); }

hid_t makeStringType() {
  const hid_t type = check(H5Tcopy(H5T_C_S1), "H5Tcopy");
  check(H5Tset_size(type, H5T_VARIABLE), "H5Tset_size");
  check(H5Tset_cset(type, H5T_CSET_UTF8), "H5Tset_cset");
  return type;
}

Handle openAttribute(const Handle& object, const std::string& name) {
  return Handle(check(H5Aopen(object.get(), name.c_str(), H5P_DEFAULT),
                      "attribute '" + name + "'"));
}

template <class T>
void writeScalarAttribute(const Handle& object, const std::string& name, hid_t type,
                          const T& value) {
  if (H5Aexists(object.get(), name.c_str()) > 0) H5Adelete(object.get(), name.c_str());
  const Handle space(check(H5Screate(H5S_SCALAR), "H5Screate"));
  const Handle attribute(check(
      H5Acreate2(object.get(), name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
      "creating attribute '" + name + "'"));
  check(H5Awrite(attribute.get(), type, &value), "writing attribute '" + name + "'");
}

}  // namespace

void Handle::reset() {
  if (id_ < 0) return;
  switch (H5Iget_type(id_)) {
    case H5I_FILE: H5Fclose(id_); break;
    case H5I_GROUP: H5Gclose(id_); break;
    case H5I_DATASET: H5Dclose(id_); break;
    case H5I_DATASPACE: H5Sclose(id_); break;
    case H5I_DATATYPE: H5Tclose(id_); break;
    case H5I_ATTR: H5Aclose(id_); break;
    case H5I_GENPROP_LST: H5Pclose(id_); break;
    default: break;
  }
  id_ = H5I_INVALID_HID;
}

std::string takeErrorStack() {
  std::vector<std::string> entries;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collectError, &entries);
  H5Eclear2(H5E_DEFAULT);
  if (entries.empty()) return "no reason given";
  std::string text = entries.front();
  for (std::size_t i = 1; i < std::min<std::size_t>(entries.size(), 4); ++i) text += "; " + entries[i];
  if (entries.size() > 5) text += "; ...";
  if (entries.size() > 4) text += "; " + entries.back();
  return text;
}

hid_t check(hid_t id, const std::string& what) {
  if (id < 0) throw Hdf5Error(what + ": " + takeErrorStack());
  return id;
}

void check(herr_t status, const std::string& what) {
  if (status < 0) throw Hdf5Error(what + ": " + takeErrorStack());
}

Handle createFile(const std::string& path, unsigned root_links) {
  silenceHdf5();
  const Handle fcpl = createTypedProperties(H5P_FILE_CREATE);
  // A file cut short (a full disk, a copy that stopped) keeps every
  // trajectory written entirely before the cut (everything else lies
  // after the root group's first header chunk, ~36 KB for 1024 links):
  // - the root's links stay in that chunk, presized for `root_links` (the
  //   trajectories the run will write, at least 1024): a link past it goes
  //   to a continuation chunk further on, and a cut before that chunk makes
  //   the whole root unreadable (HDF5 checks every chunk of a header), so
  //   with 4000 groups in a header sized for 1024 a cut at 60 % of the file
  //   lost all of them; presized for 4000, it kept every group before the
  //   cut. Growing the header is also slow: 3000 groups took 12.4 s of CPU
  //   with 1024 presized, 0.8 s with 3000 (HDF5 1.10.8, one 800-byte
  //   dataset each). Links stay compact up to 60000 (dense storage, HDF5's
  //   default above 8 links, keeps its index at the file's end);
  // - nothing is ever allocated but at the end of the file (no free-space
  //   reuse), so a trajectory's objects all precede the next one's;
  // - the root's attributes stay in its header (compact), the set's
  //   description in group meta (see demo_file.cpp).
  check(H5Pset_link_phase_change(fcpl.get(), 60000, 50000), "H5Pset_link_phase_change");
  check(H5Pset_est_link_info(fcpl.get(), std::clamp(root_links, 1024u, 60000u), 12),
        "H5Pset_est_link_info");
  check(H5Pset_link_creation_order(fcpl.get(), H5P_CRT_ORDER_TRACKED), "H5Pset_link_creation_order");
  check(H5Pset_attr_phase_change(fcpl.get(), 64, 0), "H5Pset_attr_phase_change");
  check(H5Pset_file_space_strategy(fcpl.get(), H5F_FSPACE_STRATEGY_NONE, 0, 0),
        "H5Pset_file_space_strategy");
  const Handle fapl = createTypedProperties(H5P_FILE_ACCESS);
  check(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_LATEST, H5F_LIBVER_LATEST),
        "H5Pset_libver_bounds");
  return Handle(check(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), fapl.get()),
                      "cannot create '" + path + "'"));
}

Handle openForReading(const std::string& path) {
  silenceHdf5();
  const Handle fapl = createTypedProperties(H5P_FILE_ACCESS);
  // HDF5 refuses a file shorter than its superblock says ("truncated
  // file"); h5clear sets this same property to read one anyway. What lies
  // beyond the cut then fails on its own, trajectory by trajectory.
  hbool_t skip = 1;
  if (H5Pexist(fapl.get(), "skip_eof_check") > 0) H5Pset(fapl.get(), "skip_eof_check", &skip);
  // A reader does not lock, and ignores the "open for writing" mark of a
  // file still being generated or left by a killed run (what h5clear
  // removes): it reads what was flushed.
  check(H5Pset_file_locking(fapl.get(), false, true), "H5Pset_file_locking");
  hbool_t clear = 1;
  if (H5Pexist(fapl.get(), "clear_status_flags") > 0) H5Pset(fapl.get(), "clear_status_flags", &clear);
  H5Eclear2(H5E_DEFAULT);
  return Handle(check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get()),
                      "cannot open '" + path + "' as an HDF5 file"));
}

namespace {
uint64_t readLittleEndian(const unsigned char* bytes, std::size_t size) {
  uint64_t value = 0;
  for (std::size_t k = size; k-- > 0;) value = (value << 8) | bytes[k];
  return value;
}
}  // namespace

FileLayout readFileLayout(const std::string& path) {
  FileLayout layout;
  std::ifstream in(path, std::ios::binary);
  if (!in) return layout;
  in.seekg(0, std::ios::end);
  layout.bytes = uint64_t(in.tellg());
  in.seekg(0);
  // Superblock version 2 and 3 (HDF5 file format specification, II.A):
  // signature, version, size of offsets (O) and of lengths, flags, then
  // base address, extension address, end-of-file address, root group
  // object header address (O bytes each) and a checksum.
  unsigned char head[12] = {};
  if (!in.read(reinterpret_cast<char*>(head), sizeof head)) return layout;
  if (std::string(reinterpret_cast<char*>(head), 8) != "\x89HDF\r\n\x1a\n" || (head[8] != 2 && head[8] != 3))
    return layout;
  const std::size_t offset_size = head[9];
  if (offset_size != 4 && offset_size != 8) return layout;
  layout.superblock_end = 12 + 4 * offset_size + 4;
  unsigned char fields[32] = {};
  if (!in.read(reinterpret_cast<char*>(fields), std::streamsize(4 * offset_size))) return layout;
  layout.recorded_bytes = readLittleEndian(fields + 2 * offset_size, offset_size);
  layout.root_header = readLittleEndian(fields + 3 * offset_size, offset_size);
  // The root's version 2 object header (IV.A.1.b): "OHDR", version, flags,
  // optional times (flags bit 5) and phase change values (bit 4), the size
  // of chunk 0 in 1 << (flags & 3) bytes, the chunk, a checksum.
  in.seekg(std::streamoff(layout.root_header));
  unsigned char prefix[6 + 16 + 4 + 8] = {};
  if (!in.read(reinterpret_cast<char*>(prefix), 6)) return layout;
  if (std::string(reinterpret_cast<char*>(prefix), 4) != "OHDR") return layout;
  const unsigned flags = prefix[5];
  const std::size_t optional = ((flags & 0x20) ? 16 : 0) + ((flags & 0x10) ? 4 : 0);
  const std::size_t size_bytes = std::size_t(1) << (flags & 3);
  if (!in.read(reinterpret_cast<char*>(prefix + 6), std::streamsize(optional + size_bytes))) return layout;
  const uint64_t chunk = readLittleEndian(prefix + 6 + optional, size_bytes);
  layout.root_header_end = layout.root_header + 6 + optional + size_bytes + chunk + 4;
  return layout;
}

uint64_t calcDataEnd(const Handle& parent, const std::string& name) {
  const Handle dataset(check(H5Dopen2(parent.get(), name.c_str(), H5P_DEFAULT), "dataset '" + name + "'"));
  const Handle plist(check(H5Dget_create_plist(dataset.get()), "dataset '" + name + "': its properties"));
  uint64_t end = 0;
  switch (H5Pget_layout(plist.get())) {
    case H5D_CHUNKED: {
      // The dataset's own space (1.10.8 takes no H5S_ALL here).
      const Handle space(check(H5Dget_space(dataset.get()), "dataset '" + name + "': its space"));
      hsize_t chunks = 0;
      check(H5Dget_num_chunks(dataset.get(), space.get(), &chunks), "dataset '" + name + "': its chunks");
      for (hsize_t k = 0; k < chunks; ++k) {
        hsize_t offset[H5S_MAX_RANK] = {};
        unsigned filters = 0;
        haddr_t address = HADDR_UNDEF;
        hsize_t size = 0;
        check(H5Dget_chunk_info(dataset.get(), space.get(), k, offset, &filters, &address, &size),
              "dataset '" + name + "': chunk " + std::to_string(k));
        if (address != HADDR_UNDEF) end = std::max<uint64_t>(end, address + size);
      }
      break;
    }
    case H5D_CONTIGUOUS:
      if (const haddr_t address = H5Dget_offset(dataset.get()); address != HADDR_UNDEF)
        end = address + H5Dget_storage_size(dataset.get());
      break;
    default: break;
  }
  H5Eclear2(H5E_DEFAULT);  // H5Dget_offset's "no storage" of an empty dataset
  return end;
}

void flushFile(const Handle& file) { check(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "H5Fflush"); }

Handle createGroup(const Handle& parent, const std::string& name, unsigned links) {
  const Handle gcpl = createTypedProperties(H5P_GROUP_CREATE);
  check(H5Pset_est_link_info(gcpl.get(), links, 16), "H5Pset_est_link_info");
  // Links stay in the group's header (compact) up to `links`, not in HDF5's
  // dense storage (above 8 by default): a header carries a checksum, the
  // fractal heap holding dense links does not, and HDF5 1.10.8 crashed
  // (SIGSEGV in H5G__dense_iterate) listing a trajectory group whose heap
  // lay past the end of a file cut short.
  check(H5Pset_link_phase_change(gcpl.get(), std::max(links, 8u), 6), "H5Pset_link_phase_change");
  // Attributes too (group meta has 11; dense above 8), as the root's.
  check(H5Pset_attr_phase_change(gcpl.get(), 64, 0), "H5Pset_attr_phase_change");
  check(H5Pset_link_creation_order(gcpl.get(), H5P_CRT_ORDER_TRACKED), "H5Pset_link_creation_order");
  return Handle(check(H5Gcreate2(parent.get(), name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT),
                      "creating group '" + name + "'"));
}

Handle openGroup(const Handle& parent, const std::string& name) {
  return Handle(check(H5Gopen2(parent.get(), name.c_str(), H5P_DEFAULT), "group '" + name + "'"));
}

bool hasDenseLinks(const Handle& group) {
  H5G_info_t info{};
  check(H5Gget_info(group.get(), &info), "the group's link storage");
  return info.storage_type == H5G_STORAGE_TYPE_DENSE;
}

bool hasLink(const Handle& parent, const std::string& name) {
  const htri_t exists = H5Lexists(parent.get(), name.c_str(), H5P_DEFAULT);
  if (exists < 0) H5Eclear2(H5E_DEFAULT);
  return exists > 0;
}

std::vector<std::string> listLinks(const Handle& group) {
  std::vector<std::string> names;
  auto collect = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->push_back(name);
    return 0;
  };
  hsize_t index = 0;
  if (H5Literate(group.get(), H5_INDEX_CRT_ORDER, H5_ITER_INC, &index, collect, &names) < 0) {
    H5Eclear2(H5E_DEFAULT);
    names.clear();
    index = 0;
    check(H5Literate(group.get(), H5_INDEX_NAME, H5_ITER_INC, &index, collect, &names),
          "listing the links of a group");
  }
  return names;
}

template <> hid_t getMemoryType<double>() { return H5T_NATIVE_DOUBLE; }
template <> hid_t getMemoryType<float>() { return H5T_NATIVE_FLOAT; }
template <> hid_t getMemoryType<uint8_t>() { return H5T_NATIVE_UINT8; }
template <> hid_t getMemoryType<uint32_t>() { return H5T_NATIVE_UINT32; }
template <> hid_t getMemoryType<uint64_t>() { return H5T_NATIVE_UINT64; }

namespace {
template <class T> hid_t getFileType();
template <> hid_t getFileType<double>() { return H5T_IEEE_F64LE; }
template <> hid_t getFileType<float>() { return H5T_IEEE_F32LE; }
template <> hid_t getFileType<uint8_t>() { return H5T_STD_U8LE; }
template <> hid_t getFileType<uint32_t>() { return H5T_STD_U32LE; }
template <> hid_t getFileType<uint64_t>() { return H5T_STD_U64LE; }
}  // namespace

template <class T>
void writeDataset(const Handle& parent, const std::string& name, const std::vector<hsize_t>& dims,
                  const T* data, hsize_t rows_per_chunk) {
  const Handle space(check(H5Screate_simple(int(dims.size()), dims.data(), nullptr), "H5Screate_simple"));
  const Handle dcpl = createTypedProperties(H5P_DATASET_CREATE);
  hsize_t elements = 1;
  for (hsize_t d : dims) elements *= d;
  if (elements > 0) {
    // One chunk per `rows_per_chunk` rows (0: as many as fit ~1 MiB).
    std::vector<hsize_t> chunk = dims;
    hsize_t row = sizeof(T);
    for (std::size_t k = 1; k < dims.size(); ++k) row *= dims[k];
    if (rows_per_chunk == 0) rows_per_chunk = std::max<hsize_t>(1, (hsize_t(1) << 20) / row);
    chunk[0] = std::min(dims[0], rows_per_chunk);
    check(H5Pset_chunk(dcpl.get(), int(chunk.size()), chunk.data()), "H5Pset_chunk");
    check(H5Pset_shuffle(dcpl.get()), "H5Pset_shuffle");
    check(H5Pset_deflate(dcpl.get(), 1), "H5Pset_deflate");
  }
  const Handle dataset(check(H5Dcreate2(parent.get(), name.c_str(), getFileType<T>(), space.get(),
                                        H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                             "creating dataset '" + name + "'"));
  if (elements > 0)
    check(H5Dwrite(dataset.get(), getMemoryType<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
          "writing dataset '" + name + "'");
}

std::vector<hsize_t> readDims(const Handle& parent, const std::string& name) {
  const Handle dataset(check(H5Dopen2(parent.get(), name.c_str(), H5P_DEFAULT), "dataset '" + name + "'"));
  const Handle space(check(H5Dget_space(dataset.get()), "dataset '" + name + "': its space"));
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) throw Hdf5Error("dataset '" + name + "': " + takeErrorStack());
  std::vector<hsize_t> dims(std::size_t(rank), 0);
  check(H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr), "dataset '" + name + "': dims");
  return dims;
}

ElementType readElementType(const Handle& parent, const std::string& name) {
  const Handle dataset(check(H5Dopen2(parent.get(), name.c_str(), H5P_DEFAULT), "dataset '" + name + "'"));
  const Handle type(check(H5Dget_type(dataset.get()), "dataset '" + name + "': its type"));
  return {H5Tget_size(type.get()), H5Tget_class(type.get()) == H5T_FLOAT};
}

template <class T>
std::vector<T> readDataset(const Handle& parent, const std::string& name, std::vector<hsize_t>* dims_out) {
  const std::vector<hsize_t> dims = readDims(parent, name);
  const Handle dataset(check(H5Dopen2(parent.get(), name.c_str(), H5P_DEFAULT), "dataset '" + name + "'"));
  const Handle type(check(H5Dget_type(dataset.get()), "dataset '" + name + "': its type"));
  const bool want_float = std::is_floating_point_v<T>;
  if ((H5Tget_class(type.get()) == H5T_FLOAT) != want_float)
    throw Hdf5Error("dataset '" + name + "' holds " +
                    (want_float ? "integers where numbers with a fraction" : "floats where integers") +
                    " are expected");
  hsize_t elements = 1;
  for (hsize_t d : dims) elements *= d;
  std::vector<T> data(elements);
  if (elements > 0)
    check(H5Dread(dataset.get(), getMemoryType<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()),
          "reading dataset '" + name + "'");
  if (dims_out) *dims_out = dims;
  return data;
}

#define MANIBENCH_DEMOS_DATASET_TYPE(T)                                                          \
  template void writeDataset<T>(const Handle&, const std::string&, const std::vector<hsize_t>&, \
                                const T*, hsize_t);                                              \
  template std::vector<T> readDataset<T>(const Handle&, const std::string&, std::vector<hsize_t>*);
MANIBENCH_DEMOS_DATASET_TYPE(double)
MANIBENCH_DEMOS_DATASET_TYPE(float)
MANIBENCH_DEMOS_DATASET_TYPE(uint8_t)
MANIBENCH_DEMOS_DATASET_TYPE(uint32_t)
MANIBENCH_DEMOS_DATASET_TYPE(uint64_t)
#undef MANIBENCH_DEMOS_DATASET_TYPE

// Strings are written fixed-length (HDF5 keeps variable-length ones in a
// global heap that may lie anywhere in the file: a file cut short would
// lose its description).
Handle makeFixedStringType(std::size_t size) {
  Handle type(check(H5Tcopy(H5T_C_S1), "H5Tcopy"));
  check(H5Tset_size(type.get(), std::max<std::size_t>(1, size)), "H5Tset_size");
  check(H5Tset_strpad(type.get(), H5T_STR_NULLPAD), "H5Tset_strpad");
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "H5Tset_cset");
  return type;
}

void writeAttribute(const Handle& object, const std::string& name, const std::string& value) {
  if (H5Aexists(object.get(), name.c_str()) > 0) H5Adelete(object.get(), name.c_str());
  const Handle type = makeFixedStringType(value.size());
  const Handle space(check(H5Screate(H5S_SCALAR), "H5Screate"));
  const Handle attribute(check(
      H5Acreate2(object.get(), name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
      "creating attribute '" + name + "'"));
  std::string padded = value;
  padded.resize(std::max<std::size_t>(1, value.size()), '\0');
  check(H5Awrite(attribute.get(), type.get(), padded.data()), "writing attribute '" + name + "'");
}

void writeAttribute(const Handle& object, const std::string& name, uint64_t value) {
  writeScalarAttribute(object, name, H5T_NATIVE_UINT64, value);
}

void writeAttribute(const Handle& object, const std::string& name, double value) {
  writeScalarAttribute(object, name, H5T_NATIVE_DOUBLE, value);
}

void writeAttribute(const Handle& object, const std::string& name,
                    const std::vector<std::string>& values) {
  if (H5Aexists(object.get(), name.c_str()) > 0) H5Adelete(object.get(), name.c_str());
  std::size_t longest = 1;
  for (const std::string& v : values) longest = std::max(longest, v.size());
  const Handle type = makeFixedStringType(longest);
  const hsize_t n = values.size();
  const Handle space(check(H5Screate_simple(1, &n, nullptr), "H5Screate_simple"));
  const Handle attribute(check(H5Acreate2(object.get(), name.c_str(), type.get(), space.get(),
                                          H5P_DEFAULT, H5P_DEFAULT),
                               "creating attribute '" + name + "'"));
  std::string packed(longest * values.size(), '\0');
  for (std::size_t i = 0; i < values.size(); ++i) packed.replace(i * longest, values[i].size(), values[i]);
  if (n > 0)
    check(H5Awrite(attribute.get(), type.get(), packed.data()), "writing attribute '" + name + "'");
}

bool hasAttribute(const Handle& object, const std::string& name) {
  const htri_t exists = H5Aexists(object.get(), name.c_str());
  if (exists < 0) H5Eclear2(H5E_DEFAULT);
  return exists > 0;
}

std::string readStringAttribute(const Handle& object, const std::string& name) {
  const Handle attribute = openAttribute(object, name);
  const Handle type(check(H5Aget_type(attribute.get()), "attribute '" + name + "': its type"));
  if (H5Tget_class(type.get()) != H5T_STRING) throw Hdf5Error("attribute '" + name + "' is not a string");
  if (H5Tis_variable_str(type.get()) <= 0) {
    std::string text(H5Tget_size(type.get()), '\0');
    check(H5Aread(attribute.get(), type.get(), text.data()), "reading attribute '" + name + "'");
    return text.substr(0, text.find('\0'));
  }
  const Handle memory(makeStringType());
  char* text = nullptr;
  check(H5Aread(attribute.get(), memory.get(), &text), "reading attribute '" + name + "'");
  std::string value = text ? text : "";
  H5free_memory(text);
  return value;
}

uint64_t readUintAttribute(const Handle& object, const std::string& name) {
  const Handle attribute = openAttribute(object, name);
  uint64_t value = 0;
  check(H5Aread(attribute.get(), H5T_NATIVE_UINT64, &value), "reading attribute '" + name + "'");
  return value;
}

double readDoubleAttribute(const Handle& object, const std::string& name) {
  const Handle attribute = openAttribute(object, name);
  double value = 0;
  check(H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, &value), "reading attribute '" + name + "'");
  return value;
}

std::vector<std::string> readStringsAttribute(const Handle& object, const std::string& name) {
  const Handle attribute = openAttribute(object, name);
  const Handle space(check(H5Aget_space(attribute.get()), "attribute '" + name + "': its space"));
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n < 0) throw Hdf5Error("attribute '" + name + "': " + takeErrorStack());
  const Handle type(check(H5Aget_type(attribute.get()), "attribute '" + name + "': its type"));
  if (H5Tget_class(type.get()) != H5T_STRING) throw Hdf5Error("attribute '" + name + "' is not a string");
  if (H5Tis_variable_str(type.get()) <= 0) {
    const std::size_t size = H5Tget_size(type.get());
    std::string packed(size * std::size_t(n), '\0');
    if (n > 0) check(H5Aread(attribute.get(), type.get(), packed.data()), "reading attribute '" + name + "'");
    std::vector<std::string> values;
    for (hssize_t i = 0; i < n; ++i) {
      const std::string item = packed.substr(std::size_t(i) * size, size);
      values.push_back(item.substr(0, item.find('\0')));
    }
    return values;
  }
  const Handle memory(makeStringType());
  std::vector<char*> texts(std::size_t(n), nullptr);
  if (n > 0) check(H5Aread(attribute.get(), memory.get(), texts.data()), "reading attribute '" + name + "'");
  std::vector<std::string> values;
  for (char* t : texts) values.emplace_back(t ? t : "");
  if (n > 0) H5Dvlen_reclaim(memory.get(), space.get(), H5P_DEFAULT, texts.data());
  return values;
}

}  // namespace manibench::demos_detail
