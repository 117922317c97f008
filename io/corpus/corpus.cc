#include "io/corpus/corpus.h"

#include <fcntl.h>
#include <libdeflate.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <system_error>
#include <thread>
#include <utility>

#include "core/error.h"
#include "core/file_util.h"
#include "core/progress.h"
#include "io/corpus/corpus_testing.h"
#include "io/corpus/hdf5_util.h"

#ifndef CSW_VERSION
#define CSW_VERSION "unknown"
#endif

namespace csw {
namespace {

namespace fs = std::filesystem;
using h5::Handle;
using h5::Where;

constexpr char kFormatName[] = "csw-corpus";
// Analog channels are chunked in blocks of about this many bytes.
constexpr int64_t kAnalogChunkBytes = 256 * 1024;
// Largest marker array LoadTake agrees to allocate (floats).
constexpr int64_t kMaxLoadFloats = int64_t{1} << 31;

std::string TakeObject(const std::string& name) { return "/takes/" + name; }

// HDF5's shuffle filter for 4-byte elements: byte j of element i goes to
// j * n + i, so the slowly varying sign/exponent bytes end up together.
void Shuffle4(const float* in, size_t n, uint8_t* out) {
  const auto* bytes = reinterpret_cast<const uint8_t*>(in);
  uint8_t* o0 = out;
  uint8_t* o1 = out + n;
  uint8_t* o2 = out + 2 * n;
  uint8_t* o3 = out + 3 * n;
  for (size_t i = 0; i < n; ++i) {
    o0[i] = bytes[4 * i];
    o1[i] = bytes[4 * i + 1];
    o2[i] = bytes[4 * i + 2];
    o3[i] = bytes[4 * i + 3];
  }
}

struct CompressorDeleter {
  void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
};

ParseError Damaged(const Where& where, const std::string& what) {
  return ParseError({where.file, std::nullopt, std::nullopt}, what);
}

std::string Errno() { return std::strerror(errno); }

void ValidateTakeName(const std::string& name) {
  if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos ||
      name.find('\0') != std::string::npos) {
    throw InvalidInput("invalid take name '" + name + "': it must be non-empty, not '.' or '..', and contain no '/'");
  }
}

// Group name of tier `index`: a zero-padded index (so that name order is tier
// order) then the tier name with '/' replaced.
std::string TierGroupName(size_t index, const std::string& name) {
  char prefix[32];
  std::snprintf(prefix, sizeof prefix, "%03zu_", index);
  std::string safe = name;
  std::replace(safe.begin(), safe.end(), '/', '_');
  return prefix + safe;
}

// The leading decimal index of a tier group name, or -1.
int64_t TierGroupIndex(const std::string& group_name) {
  int64_t v = 0;
  size_t i = 0;
  for (; i < group_name.size() && i < 12 && group_name[i] >= '0' && group_name[i] <= '9'; ++i) {
    v = v * 10 + (group_name[i] - '0');
  }
  return i == 0 ? -1 : v;
}

void DeleteLinkIfExists(hid_t loc, const std::string& name, const Where& where, const std::string& object) {
  if (h5::LinkExists(loc, name)) h5::Check(H5Ldelete(loc, name.c_str(), H5P_DEFAULT), where, "cannot delete", object);
}

Handle FileAccessList(const Where& where) {
  Handle fapl = h5::Own(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, where, "cannot create file access properties", "");
  // Objects readable by HDF5 1.8 (older MATLAB releases), with dense storage
  // for large attributes.
  h5::Check(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_V18), where, "cannot set file format bounds",
            "");
  // Lock the file where the file system allows it, and still work where it
  // does not (some network file systems).
  h5::Check(H5Pset_file_locking(fapl.get(), true, true), where, "cannot set file locking", "");
  // Closing the file fails loudly if we leaked an object handle.
  h5::Check(H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_SEMI), where, "cannot set close degree", "");
  return fapl;
}

// Opens an HDF5 file (the corpus or its temporary copy), turning the failure
// modes into one clear error about `where.file`.
Handle OpenHdf5(const std::string& file, unsigned flags, const Where& where) {
  std::error_code ec;
  if (!fs::exists(file, ec)) throw IoError(where.file, "no such file");
  if (fs::is_directory(file, ec)) throw IoError(where.file, "is a directory, not a corpus file");
  if (::access(file.c_str(), R_OK) != 0) throw IoError(where.file, "cannot read: " + Errno());
  htri_t is_hdf5 = H5Fis_hdf5(file.c_str());
  if (is_hdf5 == 0) {
    h5::TakeErrorMessage();
    throw Damaged(where, "not an HDF5 file (no HDF5 signature), so not a csw corpus");
  }
  if (is_hdf5 < 0) throw IoError(where.file, "cannot read as HDF5: " + h5::TakeErrorMessage());
  Handle fapl = FileAccessList(where);
  hid_t id = H5Fopen(file.c_str(), flags, fapl.get());
  if (id < 0) throw Damaged(where, "damaged or truncated HDF5 file: " + h5::TakeErrorMessage());
  return Handle(id, H5Fclose);
}

// Where an external link points.
struct LinkTarget {
  bool external = false;
  std::string file;    // as stored in the link, e.g. "corpus.h5.d/take01-….h5"
  std::string object;  // path inside that file
};

LinkTarget LinkTargetOf(hid_t group, const std::string& name) {
  LinkTarget t;
  H5L_info_t info;
  if (H5Lget_info(group, name.c_str(), &info, H5P_DEFAULT) < 0) {
    H5Eclear2(H5E_DEFAULT);
    return t;
  }
  if (info.type != H5L_TYPE_EXTERNAL) return t;
  std::vector<char> buf(info.u.val_size + 1, '\0');
  const char* file = nullptr;
  const char* object = nullptr;
  unsigned flags = 0;
  if (H5Lget_val(group, name.c_str(), buf.data(), info.u.val_size, H5P_DEFAULT) < 0 ||
      H5Lunpack_elink_val(buf.data(), info.u.val_size, &flags, &file, &object) < 0 || file == nullptr ||
      object == nullptr) {
    H5Eclear2(H5E_DEFAULT);
    return t;
  }
  t.external = true;
  t.file = file;
  t.object = object;
  return t;
}

// A file named by an external link of the corpus at corpus_path: relative
// names are relative to the corpus file's folder (as HDF5 resolves them).
std::string InCorpusDir(const std::string& corpus_path, const std::string& rel) {
  if (fs::path(rel).is_absolute()) return rel;
  fs::path dir = fs::path(corpus_path).parent_path();
  return (dir.empty() ? fs::path(rel) : dir / rel).string();
}

IoError MissingTakeFile(const std::string& corpus, const std::string& take, const std::string& rel) {
  std::string folder = fs::path(rel).parent_path().string();
  if (folder.empty()) folder = rel;
  return IoError(corpus, "take '" + take + "': its file " + rel + " is missing; the folder " + folder +
                             " must stay beside " + fs::path(corpus).filename().string() +
                             " (use csw pack to send one file)");
}

// Checks the root attributes and every take: the shape of markers stored in
// this file, and that every file an external link names exists. Appends the
// files the links name to `referenced`.
void ValidateCorpus(hid_t file, const Where& where, std::vector<std::string>* referenced) {
  auto format = h5::ReadAttrString(file, "format", where, "/");
  if (!format) throw Damaged(where, "not a csw corpus: the root group has no 'format' attribute");
  if (*format != kFormatName) throw Damaged(where, "not a csw corpus: format is '" + *format + "'");
  auto version = h5::ReadAttrInt(file, "format_version", where, "/");
  if (!version) throw Damaged(where, "csw corpus without a format_version attribute");
  if (*version > kCorpusFormatVersion) {
    throw Damaged(where, "corpus format_version " + std::to_string(*version) + " is newer than this csw reads (" +
                             std::to_string(kCorpusFormatVersion) + "); update csw");
  }
  if (*version < 1) throw Damaged(where, "invalid corpus format_version " + std::to_string(*version));
  if (!h5::LinkExists(file, "takes")) throw Damaged(where, "csw corpus without a /takes group");
  Handle takes = h5::OpenGroup(file, "takes", where, "/takes");
  for (const std::string& name : h5::LinkNames(takes.get(), where, "/takes")) {
    const std::string obj = TakeObject(name);
    const std::string prefix = "take '" + name + "': ";
    hid_t gid = H5Gopen2(takes.get(), name.c_str(), H5P_DEFAULT);
    if (gid < 0) throw Damaged(where, prefix + obj + " is not a readable group (" + h5::TakeErrorMessage() + ")");
    Handle group(gid, H5Gclose);
    if (!h5::LinkExists(group.get(), "markers")) throw Damaged(where, prefix + obj + "/markers is missing");
    if (!h5::LinkExists(group.get(), "marker_names")) throw Damaged(where, prefix + obj + "/marker_names is missing");
    bool markers_linked = false;
    std::string last;
    for (const std::string& member : h5::LinkNames(group.get(), where, obj)) {
      LinkTarget target = LinkTargetOf(group.get(), member);
      if (!target.external) continue;
      if (member == "markers") markers_linked = true;
      if (target.file == last) continue;
      last = target.file;
      std::error_code ec;
      if (!fs::exists(InCorpusDir(where.file, target.file), ec)) throw MissingTakeFile(where.file, name, target.file);
      if (referenced != nullptr) referenced->push_back(target.file);
    }
    // Markers in another file are checked when they are read (LoadTake); the
    // index caches their shape.
    if (markers_linked) continue;
    hid_t did = H5Dopen2(group.get(), "markers", H5P_DEFAULT);
    if (did < 0)
      throw Damaged(where, prefix + obj + "/markers is not a readable dataset (" + h5::TakeErrorMessage() + ")");
    Handle markers(did, H5Dclose);
    std::vector<hsize_t> dims = h5::Shape(markers.get(), where, obj + "/markers");
    if (dims.size() != 3) {
      throw Damaged(where, prefix + obj + "/markers has rank " + std::to_string(dims.size()) + ", expected 3");
    }
    if (dims[2] != 3) {
      throw Damaged(where, prefix + obj + "/markers has last dimension " + std::to_string(dims[2]) + ", expected 3");
    }
    Handle type = h5::Own(H5Dget_type(markers.get()), H5Tclose, where, "cannot read the type of", obj + "/markers");
    if (H5Tget_class(type.get()) != H5T_FLOAT) throw Damaged(where, prefix + obj + "/markers is not floating point");
    hid_t nid = H5Dopen2(group.get(), "marker_names", H5P_DEFAULT);
    if (nid < 0) throw Damaged(where, prefix + obj + "/marker_names is not a readable dataset");
    Handle names(nid, H5Dclose);
    std::vector<hsize_t> ndims = h5::Shape(names.get(), where, obj + "/marker_names");
    if (ndims.size() != 1 || ndims[0] != dims[1]) {
      throw Damaged(where, prefix + obj + "/marker_names has " +
                               (ndims.size() == 1 ? std::to_string(ndims[0]) : std::string("a non-vector of")) +
                               " names but markers has " + std::to_string(dims[1]) + " markers");
    }
  }
}
struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

// Chunk frames of a markers dataset laid out as csw writes it (little-endian
// float32, chunks of [C][markers][3], shuffle then deflate), or 0 otherwise.
int64_t FastChunkFrames(hid_t dataset, int64_t markers) {
  if constexpr (std::endian::native != std::endian::little) return 0;
  int64_t result = 0;
  hid_t type = H5Dget_type(dataset);
  hid_t dcpl = H5Dget_create_plist(dataset);
  if (type >= 0 && dcpl >= 0 && H5Tequal(type, H5T_IEEE_F32LE) > 0 && H5Pget_layout(dcpl) == H5D_CHUNKED &&
      H5Pget_nfilters(dcpl) == 2) {
    hsize_t chunk[3] = {0, 0, 0};
    unsigned flags = 0;
    size_t nelmts = 0;
    bool shuffle = H5Pget_filter2(dcpl, 0, &flags, &nelmts, nullptr, 0, nullptr, nullptr) == H5Z_FILTER_SHUFFLE;
    nelmts = 0;
    bool deflate = H5Pget_filter2(dcpl, 1, &flags, &nelmts, nullptr, 0, nullptr, nullptr) == H5Z_FILTER_DEFLATE;
    if (shuffle && deflate && H5Pget_chunk(dcpl, 3, chunk) == 3 && chunk[1] == static_cast<hsize_t>(markers) &&
        chunk[2] == 3 && chunk[0] > 0) {
      result = static_cast<int64_t>(chunk[0]);
    }
  }
  if (dcpl >= 0) H5Pclose(dcpl);
  if (type >= 0) H5Tclose(type);
  H5Eclear2(H5E_DEFAULT);
  return result;
}

// Reads frames [first, first + count) of a markers dataset written by csw by
// reading the raw chunks and inflating them with libdeflate (about three times
// faster than HDF5's zlib path). Returns false, having written nothing
// reliable, when any chunk is not as expected; the caller then reads through HDF5.
bool ReadMarkerRangeFast(hid_t dataset, int64_t first, int64_t count, int64_t markers, int64_t chunk_frames,
                         float* out) {
  const size_t chunk_values = static_cast<size_t>(chunk_frames * markers * 3);
  const size_t chunk_bytes = chunk_values * sizeof(float);
  std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> dec(libdeflate_alloc_decompressor());
  if (!dec) return false;
  std::vector<uint8_t> raw;
  std::vector<uint8_t> shuffled(chunk_bytes);
  const int64_t row = markers * 3;
  for (int64_t k = first / chunk_frames; k * chunk_frames < first + count; ++k) {
    hsize_t offset[3] = {static_cast<hsize_t>(k * chunk_frames), 0, 0};
    hsize_t stored = 0;
    if (H5Dget_chunk_storage_size(dataset, offset, &stored) < 0 || stored == 0 || stored > 2 * chunk_bytes + 1024) {
      H5Eclear2(H5E_DEFAULT);
      return false;
    }
    raw.resize(stored);
    uint32_t filter_mask = 0;
    if (H5Dread_chunk(dataset, H5P_DEFAULT, offset, &filter_mask, raw.data()) < 0 || filter_mask != 0) {
      H5Eclear2(H5E_DEFAULT);
      return false;
    }
    size_t actual = 0;
    if (libdeflate_zlib_decompress(dec.get(), raw.data(), raw.size(), shuffled.data(), chunk_bytes, &actual) !=
            LIBDEFLATE_SUCCESS ||
        actual != chunk_bytes) {
      return false;
    }
    // Unshuffle only the frames of this chunk that were asked for.
    const int64_t lo = std::max(first, k * chunk_frames);
    const int64_t hi = std::min(first + count, (k + 1) * chunk_frames);
    const size_t begin = static_cast<size_t>((lo - k * chunk_frames) * row);
    const size_t end = static_cast<size_t>((hi - k * chunk_frames) * row);
    auto* dst = reinterpret_cast<uint8_t*>(out + (lo - first) * row);
    const uint8_t* p0 = shuffled.data() + begin;
    const uint8_t* p1 = p0 + chunk_values;
    const uint8_t* p2 = p1 + chunk_values;
    const uint8_t* p3 = p2 + chunk_values;
    for (size_t i = 0; i < end - begin; ++i) {
      dst[4 * i] = p0[i];
      dst[4 * i + 1] = p1[i];
      dst[4 * i + 2] = p2[i];
      dst[4 * i + 3] = p3[i];
    }
  }
  return true;
}

// Reads frames [first, first + count) of an open markers dataset into out.
void ReadMarkerRange(hid_t dataset, int64_t first, int64_t count, int64_t markers, float* out, const Where& where,
                     const std::string& object) {
  if (count == 0 || markers == 0) return;
  if (int64_t chunk_frames = FastChunkFrames(dataset, markers);
      chunk_frames > 0 && ReadMarkerRangeFast(dataset, first, count, markers, chunk_frames, out)) {
    return;
  }
  Handle fspace = h5::Own(H5Dget_space(dataset), H5Sclose, where, "cannot read", object);
  hsize_t start[3] = {static_cast<hsize_t>(first), 0, 0};
  hsize_t cnt[3] = {static_cast<hsize_t>(count), static_cast<hsize_t>(markers), 3};
  h5::Check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, cnt, nullptr), where, "cannot select",
            object);
  Handle mspace = h5::Own(H5Screate_simple(3, cnt, nullptr), H5Sclose, where, "cannot read", object);
  h5::Check(H5Dread(dataset, H5T_NATIVE_FLOAT, mspace.get(), fspace.get(), H5P_DEFAULT, out), where, "cannot read",
            object);
}

// Reads a whole 2-D float dataset; returns rows and fills cols.
std::vector<float> ReadFloat2D(hid_t loc, const std::string& name, int64_t* rows, int64_t* cols, const Where& where,
                               const std::string& object) {
  Handle ds = h5::OpenDataset(loc, name, where, object);
  std::vector<hsize_t> dims = h5::Shape(ds.get(), where, object);
  if (dims.size() != 2) throw Damaged(where, object + " has rank " + std::to_string(dims.size()) + ", expected 2");
  if (dims[1] > 0 && dims[0] > static_cast<hsize_t>(kMaxLoadFloats) / dims[1]) {
    throw Damaged(where, object + " is implausibly large");
  }
  *rows = static_cast<int64_t>(dims[0]);
  *cols = static_cast<int64_t>(dims[1]);
  std::vector<float> out(dims[0] * dims[1]);
  if (!out.empty()) {
    h5::Check(H5Dread(ds.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), where, "cannot read",
              object);
  }
  return out;
}

// Creates an extendible 2-D float dataset [0][cols] chunked by rows, shuffle + deflate.
Handle CreateExtendible2D(hid_t loc, const std::string& name, int64_t cols, int64_t chunk_rows, const Where& where,
                          const std::string& object) {
  hsize_t dims[2] = {0, static_cast<hsize_t>(cols)};
  hsize_t maxdims[2] = {H5S_UNLIMITED, static_cast<hsize_t>(cols)};
  hsize_t chunk[2] = {static_cast<hsize_t>(std::max<int64_t>(1, chunk_rows)),
                      static_cast<hsize_t>(std::max<int64_t>(1, cols))};
  Handle space = h5::Own(H5Screate_simple(2, dims, maxdims), H5Sclose, where, "cannot create", object);
  Handle dcpl = h5::Own(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, where, "cannot create", object);
  h5::Check(H5Pset_chunk(dcpl.get(), 2, chunk), where, "cannot chunk", object);
  h5::Check(H5Pset_shuffle(dcpl.get()), where, "cannot set the shuffle filter of", object);
  h5::Check(H5Pset_deflate(dcpl.get(), kCorpusDeflateLevel), where, "cannot set the deflate filter of", object);
  return h5::Own(H5Dcreate2(loc, name.c_str(), H5T_IEEE_F32LE, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                 H5Dclose, where, "cannot create", object);
}

// Appends rows × cols floats at the end of an extendible 2-D dataset.
void Append2D(hid_t dataset, int64_t old_rows, int64_t rows, int64_t cols, const float* data, const Where& where,
              const std::string& object) {
  if (rows == 0) return;
  hsize_t new_dims[2] = {static_cast<hsize_t>(old_rows + rows), static_cast<hsize_t>(cols)};
  h5::Check(H5Dset_extent(dataset, new_dims), where, "cannot extend", object);
  if (cols == 0) return;
  Handle fspace = h5::Own(H5Dget_space(dataset), H5Sclose, where, "cannot write", object);
  hsize_t start[2] = {static_cast<hsize_t>(old_rows), 0};
  hsize_t cnt[2] = {static_cast<hsize_t>(rows), static_cast<hsize_t>(cols)};
  h5::Check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, cnt, nullptr), where, "cannot select",
            object);
  Handle mspace = h5::Own(H5Screate_simple(2, cnt, nullptr), H5Sclose, where, "cannot write", object);
  h5::Check(H5Dwrite(dataset, H5T_NATIVE_FLOAT, mspace.get(), fspace.get(), H5P_DEFAULT, data), where, "cannot write",
            object);
}

std::vector<std::string> PadTo(std::vector<std::string> v, size_t n) {
  v.resize(n);
  return v;
}

// The skeleton of a take as the JSON text of the `skeleton` attribute of
// `orientations` (docs/corpus-format.md).
std::string SkeletonJson(const std::vector<SkeletonJoint>& skeleton) {
  nlohmann::json joints = nlohmann::json::array();
  for (const SkeletonJoint& j : skeleton) {
    joints.push_back({{"name", j.name},
                      {"parent", j.parent},
                      {"offset_mm", {j.offset_mm[0], j.offset_mm[1], j.offset_mm[2]}},
                      {"channels", j.channels},
                      {"end_site", j.end_site}});
  }
  return joints.dump();
}

std::vector<SkeletonJoint> ParseSkeletonJson(const std::string& text, const Where& where, const std::string& object) {
  std::vector<SkeletonJoint> out;
  try {
    const nlohmann::json joints = nlohmann::json::parse(text);
    if (!joints.is_array()) throw Damaged(where, object + ": the skeleton attribute is not a JSON array");
    for (const nlohmann::json& j : joints) {
      SkeletonJoint s;
      s.name = j.at("name").get<std::string>();
      s.parent = j.at("parent").get<int>();
      const nlohmann::json& o = j.at("offset_mm");
      if (!o.is_array() || o.size() != 3) throw Damaged(where, object + ": a skeleton offset_mm is not 3 numbers");
      for (int k = 0; k < 3; ++k) s.offset_mm[k] = o[static_cast<size_t>(k)].get<double>();
      s.channels = j.at("channels").get<std::vector<std::string>>();
      s.end_site = j.at("end_site").get<bool>();
      if (s.parent < -1 || s.parent >= static_cast<int>(out.size())) {
        throw Damaged(where, object + ": skeleton joint '" + s.name + "' has parent " + std::to_string(s.parent) +
                                 " (parents must come first)");
      }
      out.push_back(std::move(s));
    }
  } catch (const nlohmann::json::exception& e) {
    throw Damaged(where, object + ": the skeleton attribute is not valid skeleton JSON (" + e.what() + ")");
  }
  return out;
}

// Creates the extendible orientations dataset [0][joints][4] (chunks of
// kCorpusChunkFrames frames, shuffle + deflate, fill NaN).
Handle CreateOrientations(hid_t loc, int64_t joints, const Where& where, const std::string& object) {
  hsize_t dims[3] = {0, static_cast<hsize_t>(joints), 4};
  hsize_t maxdims[3] = {H5S_UNLIMITED, static_cast<hsize_t>(joints), 4};
  hsize_t chunk[3] = {static_cast<hsize_t>(kCorpusChunkFrames), static_cast<hsize_t>(std::max<int64_t>(1, joints)), 4};
  Handle space = h5::Own(H5Screate_simple(3, dims, maxdims), H5Sclose, where, "cannot create", object);
  Handle dcpl = h5::Own(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, where, "cannot create", object);
  h5::Check(H5Pset_chunk(dcpl.get(), 3, chunk), where, "cannot chunk", object);
  h5::Check(H5Pset_shuffle(dcpl.get()), where, "cannot set the shuffle filter of", object);
  h5::Check(H5Pset_deflate(dcpl.get(), kCorpusDeflateLevel), where, "cannot set the deflate filter of", object);
  float fill = kMissing;
  h5::Check(H5Pset_fill_value(dcpl.get(), H5T_NATIVE_FLOAT, &fill), where, "cannot set the fill value of", object);
  return h5::Own(H5Dcreate2(loc, "orientations", H5T_IEEE_F32LE, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                 H5Dclose, where, "cannot create", object);
}

// Appends frames × joints × 4 floats at the end of the orientations dataset.
void AppendOrientationFrames(hid_t dataset, int64_t old_frames, int64_t frames, int64_t joints, const float* data,
                             const Where& where, const std::string& object) {
  if (frames == 0) return;
  hsize_t new_dims[3] = {static_cast<hsize_t>(old_frames + frames), static_cast<hsize_t>(joints), 4};
  h5::Check(H5Dset_extent(dataset, new_dims), where, "cannot extend", object);
  if (joints == 0) return;
  Handle fspace = h5::Own(H5Dget_space(dataset), H5Sclose, where, "cannot write", object);
  hsize_t start[3] = {static_cast<hsize_t>(old_frames), 0, 0};
  hsize_t cnt[3] = {static_cast<hsize_t>(frames), static_cast<hsize_t>(joints), 4};
  h5::Check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, cnt, nullptr), where, "cannot select",
            object);
  Handle mspace = h5::Own(H5Screate_simple(3, cnt, nullptr), H5Sclose, where, "cannot write", object);
  h5::Check(H5Dwrite(dataset, H5T_NATIVE_FLOAT, mspace.get(), fspace.get(), H5P_DEFAULT, data), where, "cannot write",
            object);
}

// Reads a take's skeleton and orientations (the `orientations` member) into t,
// whose markers are already loaded.
void ReadOrientations(hid_t take_group, Take* t, const Where& where, const std::string& obj) {
  const std::string oobj = obj + "/orientations";
  Handle ds = h5::OpenDataset(take_group, "orientations", where, oobj);
  std::vector<hsize_t> dims = h5::Shape(ds.get(), where, oobj);
  if (dims.size() != 3 || dims[2] != 4) throw Damaged(where, oobj + " is not a [frames][joints][4] array");
  const int64_t frames = static_cast<int64_t>(dims[0]);
  const int64_t joints = static_cast<int64_t>(dims[1]);
  if (joints != t->markers.markers() || frames != t->markers.frames()) {
    throw Damaged(where, oobj + " has " + std::to_string(frames) + " frames x " + std::to_string(joints) +
                             " joints but markers has " + std::to_string(t->markers.frames()) + " frames x " +
                             std::to_string(t->markers.markers()) + " markers");
  }
  std::optional<std::string> json = h5::ReadAttrString(ds.get(), "skeleton", where, oobj);
  if (!json) throw Damaged(where, oobj + " has no skeleton attribute");
  t->skeleton = ParseSkeletonJson(*json, where, oobj);
  if (static_cast<int64_t>(t->skeleton.size()) != joints) {
    throw Damaged(where, oobj + ": the skeleton has " + std::to_string(t->skeleton.size()) + " joints but the array " +
                             std::to_string(joints));
  }
  if (joints > 0 && frames > kMaxLoadFloats / (joints * 4)) {
    throw Damaged(where, oobj + " is too large to load at once");
  }
  t->orientations.Resize(frames, joints);
  if (frames > 0 && joints > 0) {
    h5::Check(H5Dread(ds.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, t->orientations.data().data()), where,
              "cannot read", oobj);
  }
}

void WriteEvents(hid_t take_group, const std::vector<Event>& events, const Where& where, const std::string& obj) {
  const std::string eobj = obj + "/events";
  Handle g = h5::CreateGroup(take_group, "events", where, eobj);
  std::vector<std::string> label, context, description;
  std::vector<double> time_s;
  for (const Event& e : events) {
    label.push_back(e.label);
    context.push_back(e.context);
    description.push_back(e.description);
    time_s.push_back(e.time_s);
  }
  h5::WriteStrings(g.get(), "label", label, where, eobj + "/label");
  h5::WriteStrings(g.get(), "context", context, where, eobj + "/context");
  h5::WriteDoubles(g.get(), "time_s", time_s, where, eobj + "/time_s");
  h5::WriteStrings(g.get(), "description", description, where, eobj + "/description");
}

void WriteTierGroups(hid_t take_group, const std::vector<LabelTier>& tiers, const Where& where,
                     const std::string& obj) {
  const std::string tobj = obj + "/tiers";
  DeleteLinkIfExists(take_group, "tiers", where, tobj);
  Handle g = h5::CreateGroup(take_group, "tiers", where, tobj);
  for (size_t i = 0; i < tiers.size(); ++i) {
    const LabelTier& tier = tiers[i];
    const std::string gname = TierGroupName(i, tier.name);
    const std::string o = tobj + "/" + gname;
    Handle tg = h5::CreateGroup(g.get(), gname, where, o);
    h5::WriteAttr(tg.get(), "name", tier.name, where, o);
    h5::WriteAttr(tg.get(), "kind", std::string(tier.kind == LabelTier::Kind::kPoint ? "point" : "interval"), where, o);
    h5::WriteAttr(tg.get(), "start_s", tier.start_s, where, o);
    h5::WriteAttr(tg.get(), "end_s", tier.end_s, where, o);
    std::vector<double> start, end;
    std::vector<std::string> text;
    for (const Label& l : tier.labels) {
      start.push_back(l.start_s);
      end.push_back(l.end_s);
      text.push_back(l.text);
    }
    h5::WriteDoubles(tg.get(), "start_s", start, where, o + "/start_s");
    h5::WriteDoubles(tg.get(), "end_s", end, where, o + "/end_s");
    h5::WriteStrings(tg.get(), "text", text, where, o + "/text");
  }
}

void CheckAudio(const Audio& audio) {
  if (audio.samples.empty()) return;
  if (audio.channels < 1) throw InvalidInput("audio has " + std::to_string(audio.channels) + " channels");
  if (audio.samples.size() % static_cast<size_t>(audio.channels) != 0) {
    throw InvalidInput("audio sample count " + std::to_string(audio.samples.size()) + " is not a multiple of " +
                       std::to_string(audio.channels) + " channels");
  }
}

void WriteAudioGroup(hid_t take_group, const Audio& audio, const std::string& source_path, const Where& where,
                     const std::string& obj) {
  const std::string aobj = obj + "/audio";
  DeleteLinkIfExists(take_group, "audio", where, aobj);
  if (audio.samples.empty() && source_path.empty()) return;
  Handle g = h5::CreateGroup(take_group, "audio", where, aobj);
  h5::WriteAttr(g.get(), "source_path", source_path, where, aobj);
  if (audio.samples.empty()) return;
  const std::string sobj = aobj + "/samples";
  hsize_t dims[2] = {static_cast<hsize_t>(audio.frames()), static_cast<hsize_t>(audio.channels)};
  Handle space = h5::Own(H5Screate_simple(2, dims, nullptr), H5Sclose, where, "cannot create", sobj);
  Handle ds =
      h5::Own(H5Dcreate2(g.get(), "samples", H5T_IEEE_F32LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
              H5Dclose, where, "cannot create", sobj);
  h5::Check(H5Dwrite(ds.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, audio.samples.data()), where,
            "cannot write", sobj);
  h5::WriteAttr(ds.get(), "rate_hz", audio.rate_hz, where, sobj);
}

void WriteProvenance(hid_t take_group, const Provenance& p, const std::string& csw_version,
                     const std::string& imported_utc, const Where& where, const std::string& obj) {
  const std::string pobj = obj + "/provenance";
  Handle g = h5::CreateGroup(take_group, "provenance", where, pobj);
  h5::WriteAttr(g.get(), "warnings", p.warnings, where, pobj);
  h5::WriteAttr(g.get(), "csw_version", csw_version, where, pobj);
  h5::WriteAttr(g.get(), "imported_utc", imported_utc, where, pobj);
  const std::string sobj = pobj + "/sources";
  Handle s = h5::CreateGroup(g.get(), "sources", where, sobj);
  std::vector<std::string> path, sha256, format;
  for (const SourceFile& f : p.sources) {
    path.push_back(f.path);
    sha256.push_back(f.sha256);
    format.push_back(f.format);
  }
  h5::WriteStrings(s.get(), "path", path, where, sobj + "/path");
  h5::WriteStrings(s.get(), "sha256", sha256, where, sobj + "/sha256");
  h5::WriteStrings(s.get(), "format", format, where, sobj + "/format");
}

std::vector<LabelTier> ReadTiers(hid_t take_group, const Where& where, const std::string& obj) {
  std::vector<LabelTier> tiers;
  if (!h5::LinkExists(take_group, "tiers")) return tiers;
  const std::string tobj = obj + "/tiers";
  Handle g = h5::OpenGroup(take_group, "tiers", where, tobj);
  std::vector<std::string> names = h5::LinkNames(g.get(), where, tobj);
  std::stable_sort(names.begin(), names.end(),
                   [](const std::string& a, const std::string& b) { return TierGroupIndex(a) < TierGroupIndex(b); });
  for (const std::string& gname : names) {
    const std::string o = tobj + "/" + gname;
    Handle tg = h5::OpenGroup(g.get(), gname, where, o);
    LabelTier tier;
    tier.name = h5::ReadAttrString(tg.get(), "name", where, o).value_or(gname);
    std::string kind = h5::ReadAttrString(tg.get(), "kind", where, o).value_or("interval");
    if (kind == "interval") {
      tier.kind = LabelTier::Kind::kInterval;
    } else if (kind == "point") {
      tier.kind = LabelTier::Kind::kPoint;
    } else {
      throw Damaged(where, o + ": unknown tier kind '" + kind + "' (expected interval or point)");
    }
    tier.start_s = h5::ReadAttrDouble(tg.get(), "start_s", where, o).value_or(0.0);
    tier.end_s = h5::ReadAttrDouble(tg.get(), "end_s", where, o).value_or(0.0);
    std::vector<double> start = h5::ReadDoubles(tg.get(), "start_s", where, o + "/start_s");
    std::vector<double> end = h5::ReadDoubles(tg.get(), "end_s", where, o + "/end_s");
    std::vector<std::string> text = h5::ReadStrings(tg.get(), "text", where, o + "/text");
    if (start.size() != end.size() || start.size() != text.size()) {
      throw Damaged(where, o + ": start_s, end_s and text have different lengths (" + std::to_string(start.size()) +
                               ", " + std::to_string(end.size()) + ", " + std::to_string(text.size()) + ")");
    }
    for (size_t i = 0; i < start.size(); ++i) tier.labels.push_back({start[i], end[i], std::move(text[i])});
    tiers.push_back(std::move(tier));
  }
  return tiers;
}

bool BadScoreName(const std::string& n) {
  return n.empty() || n == "." || n == ".." || n.find('/') != std::string::npos;
}

// The set as the group `name` of the scores group `sg` (replacing one of that name).
void WriteScoreSet(hid_t sg, const TakeScores& s, const Where& where, const std::string& obj) {
  const std::string o = obj + "/scores/" + s.name;
  DeleteLinkIfExists(sg, s.name, where, o);
  Handle g = h5::CreateGroup(sg, s.name, where, o);
  h5::WriteAttr(g.get(), "rate_hz", s.rate_hz, where, o);
  h5::WriteAttr(g.get(), "start_s", s.start_s, where, o);
  h5::WriteAttr(g.get(), "source", s.source, where, o);
  for (const ScoreMatrix& m : s.matrices) {
    const std::string mo = o + "/" + m.name;
    hsize_t dims[2] = {static_cast<hsize_t>(m.rows), static_cast<hsize_t>(m.cols)};
    Handle space = h5::Own(H5Screate_simple(2, dims, nullptr), H5Sclose, where, "cannot create", mo);
    Handle dcpl = h5::Own(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, where, "cannot create", mo);
    if (m.rows > 0 && m.cols > 0) {  // chunks of up to 1024 rows, shuffle + deflate
      hsize_t chunk[2] = {static_cast<hsize_t>(std::min<int64_t>(m.rows, 1024)), static_cast<hsize_t>(m.cols)};
      h5::Check(H5Pset_chunk(dcpl.get(), 2, chunk), where, "cannot chunk", mo);
      h5::Check(H5Pset_shuffle(dcpl.get()), where, "cannot set the shuffle filter of", mo);
      h5::Check(H5Pset_deflate(dcpl.get(), kCorpusDeflateLevel), where, "cannot set the deflate filter of", mo);
    }
    Handle ds =
        h5::Own(H5Dcreate2(g.get(), m.name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                H5Dclose, where, "cannot create", mo);
    if (!m.values.empty())
      h5::Check(H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, m.values.data()), where,
                "cannot write", mo);
    h5::WriteAttr(ds.get(), "column_names", m.column_names, where, mo);
  }
}

TakeScores ReadScoreSet(hid_t sg, const std::string& name, const Where& where, const std::string& obj) {
  const std::string o = obj + "/scores/" + name;
  Handle g = h5::OpenGroup(sg, name, where, o);
  TakeScores s;
  s.name = name;
  s.rate_hz = h5::ReadAttrDouble(g.get(), "rate_hz", where, o).value_or(0.0);
  s.start_s = h5::ReadAttrDouble(g.get(), "start_s", where, o).value_or(0.0);
  s.source = h5::ReadAttrString(g.get(), "source", where, o).value_or("");
  if (!(s.rate_hz > 0) || !std::isfinite(s.rate_hz) || !std::isfinite(s.start_s))
    throw Damaged(where, o + ": rate_hz must be a positive number and start_s finite");
  for (const std::string& mname : h5::LinkNames(g.get(), where, o)) {
    const std::string mo = o + "/" + mname;
    Handle ds = h5::OpenDataset(g.get(), mname, where, mo);
    const std::vector<hsize_t> dims = h5::Shape(ds.get(), where, mo);
    if (dims.size() != 2) throw Damaged(where, mo + " has rank " + std::to_string(dims.size()) + ", expected 2");
    if (dims[1] > 0 && dims[0] > static_cast<hsize_t>(kMaxLoadFloats) / dims[1])
      throw Damaged(where, mo + " is implausibly large");
    ScoreMatrix m;
    m.name = mname;
    m.rows = static_cast<int64_t>(dims[0]);
    m.cols = static_cast<int64_t>(dims[1]);
    m.values.resize(dims[0] * dims[1]);
    if (!m.values.empty())
      h5::Check(H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, m.values.data()), where,
                "cannot read", mo);
    m.column_names = h5::ReadAttrStrings(ds.get(), "column_names", where, mo);
    if (!m.column_names.empty() && static_cast<int64_t>(m.column_names.size()) != m.cols)
      throw Damaged(where, mo + ": " + std::to_string(m.column_names.size()) + " column names for " +
                               std::to_string(m.cols) + " columns");
    s.matrices.push_back(std::move(m));
  }
  return s;
}

struct MarkerShape {
  int64_t frames = 0;
  int64_t markers = 0;
};

MarkerShape ShapeOfMarkers(hid_t markers, const Where& where, const std::string& object) {
  std::vector<hsize_t> dims = h5::Shape(markers, where, object);
  if (dims.size() != 3 || dims[2] != 3) throw Damaged(where, object + " is not a [frames][markers][3] array");
  return {static_cast<int64_t>(dims[0]), static_cast<int64_t>(dims[1])};
}

Handle OpenTakeGroup(hid_t file, const std::string& name, const Where& where) {
  if (name.empty() || name.find('/') != std::string::npos) throw InvalidInput("no take named '" + name + "'");
  Handle takes = h5::OpenGroup(file, "takes", where, "/takes");
  if (!h5::LinkExists(takes.get(), name)) throw InvalidInput(where.file + ": no take named '" + name + "'");
  return h5::OpenGroup(takes.get(), name, where, TakeObject(name));
}

TakeSummary SummarizeTake(hid_t file, const std::string& name, const Where& where) {
  const std::string obj = TakeObject(name);
  Handle g = OpenTakeGroup(file, name, where);
  TakeSummary s;
  s.name = name;
  s.rate_hz = h5::ReadAttrDouble(g.get(), "rate_hz", where, obj).value_or(0.0);
  s.has_markerset = !h5::ReadAttrString(g.get(), "markerset", where, obj).value_or("").empty();
  // A version-2 index caches the summary, so that listing takes opens no take file.
  const hid_t gid = g.get();
  if (h5::AttrExists(gid, "frame_count") && h5::AttrExists(gid, "marker_count") && h5::AttrExists(gid, "gap_count") &&
      h5::AttrExists(gid, "has_audio") && h5::AttrExists(gid, "analog_channels")) {
    s.frames = h5::ReadAttrInt(gid, "frame_count", where, obj).value_or(0);
    s.markers = h5::ReadAttrInt(gid, "marker_count", where, obj).value_or(0);
    s.gaps = h5::ReadAttrInt(gid, "gap_count", where, obj).value_or(0);
    s.has_audio = h5::ReadAttrInt(gid, "has_audio", where, obj).value_or(0) != 0;
    s.analog_channels = h5::ReadAttrInt(gid, "analog_channels", where, obj).value_or(0);
    s.tier_names = h5::ReadAttrStrings(gid, "tier_names", where, obj);
    s.duration_s = s.rate_hz > 0 ? static_cast<double>(s.frames) / s.rate_hz : 0.0;
    return s;
  }
  Handle markers = h5::OpenDataset(g.get(), "markers", where, obj + "/markers");
  MarkerShape shape = ShapeOfMarkers(markers.get(), where, obj + "/markers");
  s.frames = shape.frames;
  s.markers = shape.markers;
  s.duration_s = s.rate_hz > 0 ? static_cast<double>(s.frames) / s.rate_hz : 0.0;
  if (auto gaps = h5::ReadAttrInt(markers.get(), "gaps", where, obj + "/markers")) {
    s.gaps = *gaps;
  } else {
    // Written by another tool: count the gaps by streaming the markers.
    constexpr int64_t kWindow = 4096;
    std::vector<uint8_t> in_gap(static_cast<size_t>(shape.markers), 0);
    std::vector<float> buf;
    for (int64_t f0 = 0; f0 < shape.frames; f0 += kWindow) {
      int64_t n = std::min(kWindow, shape.frames - f0);
      buf.resize(static_cast<size_t>(n * shape.markers * 3));
      ReadMarkerRange(markers.get(), f0, n, shape.markers, buf.data(), where, obj + "/markers");
      for (int64_t f = 0; f < n; ++f) {
        for (int64_t m = 0; m < shape.markers; ++m) {
          bool missing = std::isnan(buf[static_cast<size_t>((f * shape.markers + m) * 3)]);
          if (missing && !in_gap[static_cast<size_t>(m)]) ++s.gaps;
          in_gap[static_cast<size_t>(m)] = missing;
        }
      }
    }
  }
  for (const LabelTier& t : ReadTiers(g.get(), where, obj)) s.tier_names.push_back(t.name);
  if (h5::LinkExists(g.get(), "audio")) {
    Handle a = h5::OpenGroup(g.get(), "audio", where, obj + "/audio");
    if (h5::LinkExists(a.get(), "samples")) {
      Handle ds = h5::OpenDataset(a.get(), "samples", where, obj + "/audio/samples");
      std::vector<hsize_t> dims = h5::Shape(ds.get(), where, obj + "/audio/samples");
      s.has_audio = !dims.empty() && dims[0] > 0;
    }
  }
  if (h5::LinkExists(g.get(), "analog")) {
    Handle a = h5::OpenGroup(g.get(), "analog", where, obj + "/analog");
    if (h5::LinkExists(a.get(), "data")) {
      Handle ds = h5::OpenDataset(a.get(), "data", where, obj + "/analog/data");
      std::vector<hsize_t> dims = h5::Shape(ds.get(), where, obj + "/analog/data");
      s.analog_channels = dims.size() == 2 ? static_cast<int64_t>(dims[1]) : 0;
    }
  }
  return s;
}

Take ReadTake(hid_t file, const std::string& name, const Where& where) {
  const std::string obj = TakeObject(name);
  Handle g = OpenTakeGroup(file, name, where);
  Take t;
  t.name = name;
  t.rate_hz = h5::ReadAttrDouble(g.get(), "rate_hz", where, obj).value_or(0.0);
  t.first_frame = h5::ReadAttrInt(g.get(), "first_frame", where, obj).value_or(1);
  t.source_units = h5::ReadAttrString(g.get(), "source_units", where, obj).value_or("mm");
  t.markerset_json = h5::ReadAttrString(g.get(), "markerset", where, obj).value_or("");
  t.marker_names = h5::ReadStrings(g.get(), "marker_names", where, obj + "/marker_names");
  {
    Handle markers = h5::OpenDataset(g.get(), "markers", where, obj + "/markers");
    MarkerShape shape = ShapeOfMarkers(markers.get(), where, obj + "/markers");
    if (shape.markers != static_cast<int64_t>(t.marker_names.size())) {
      throw Damaged(where, "take '" + name + "': marker_names has " + std::to_string(t.marker_names.size()) +
                               " names but markers has " + std::to_string(shape.markers) + " markers");
    }
    if (shape.markers > 0 && shape.frames > kMaxLoadFloats / (shape.markers * 3)) {
      throw Damaged(where, "take '" + name + "': markers is too large to load at once; use LoadMarkers");
    }
    t.markers.Resize(shape.frames, shape.markers);
    ReadMarkerRange(markers.get(), 0, shape.frames, shape.markers, t.markers.data().data(), where, obj + "/markers");
  }
  if (h5::LinkExists(g.get(), "orientations")) ReadOrientations(g.get(), &t, where, obj);
  if (h5::LinkExists(g.get(), "analog")) {
    const std::string aobj = obj + "/analog";
    Handle a = h5::OpenGroup(g.get(), "analog", where, aobj);
    t.analog.names = h5::ReadStrings(a.get(), "names", where, aobj + "/names");
    if (h5::LinkExists(a.get(), "units")) t.analog.units = h5::ReadStrings(a.get(), "units", where, aobj + "/units");
    if (h5::LinkExists(a.get(), "descriptions")) {
      t.analog.descriptions = h5::ReadStrings(a.get(), "descriptions", where, aobj + "/descriptions");
    }
    if (h5::LinkExists(a.get(), "data")) {
      int64_t cols = 0;
      t.analog.data = ReadFloat2D(a.get(), "data", &t.analog.samples, &cols, where, aobj + "/data");
      if (cols != t.analog.channels()) {
        throw Damaged(where, aobj + "/data has " + std::to_string(cols) + " channels but names has " +
                                 std::to_string(t.analog.channels()));
      }
      Handle ds = h5::OpenDataset(a.get(), "data", where, aobj + "/data");
      t.analog.rate_hz = h5::ReadAttrDouble(ds.get(), "rate_hz", where, aobj + "/data").value_or(0.0);
    }
  }
  if (h5::LinkExists(g.get(), "events")) {
    const std::string eobj = obj + "/events";
    Handle e = h5::OpenGroup(g.get(), "events", where, eobj);
    std::vector<std::string> label = h5::ReadStrings(e.get(), "label", where, eobj + "/label");
    std::vector<std::string> context = h5::ReadStrings(e.get(), "context", where, eobj + "/context");
    std::vector<double> time_s = h5::ReadDoubles(e.get(), "time_s", where, eobj + "/time_s");
    std::vector<std::string> description = h5::ReadStrings(e.get(), "description", where, eobj + "/description");
    if (context.size() != label.size() || time_s.size() != label.size() || description.size() != label.size()) {
      throw Damaged(where, eobj + ": label, context, time_s and description have different lengths");
    }
    for (size_t i = 0; i < label.size(); ++i) {
      t.events.push_back({std::move(label[i]), std::move(context[i]), time_s[i], std::move(description[i])});
    }
  }
  t.tiers = ReadTiers(g.get(), where, obj);
  if (h5::LinkExists(g.get(), "audio")) {
    const std::string aobj = obj + "/audio";
    Handle a = h5::OpenGroup(g.get(), "audio", where, aobj);
    t.audio_path = h5::ReadAttrString(a.get(), "source_path", where, aobj).value_or("");
    if (h5::LinkExists(a.get(), "samples")) {
      int64_t frames = 0;
      int64_t channels = 0;
      t.audio.samples = ReadFloat2D(a.get(), "samples", &frames, &channels, where, aobj + "/samples");
      t.audio.channels = static_cast<int>(channels);
      Handle ds = h5::OpenDataset(a.get(), "samples", where, aobj + "/samples");
      t.audio.rate_hz = h5::ReadAttrDouble(ds.get(), "rate_hz", where, aobj + "/samples").value_or(0.0);
    }
  }
  t.provenance.csw_version = h5::ReadAttrString(g.get(), "csw_version", where, obj).value_or("");
  t.provenance.imported_utc = h5::ReadAttrString(g.get(), "imported_utc", where, obj).value_or("");
  if (h5::LinkExists(g.get(), "provenance")) {
    const std::string pobj = obj + "/provenance";
    Handle p = h5::OpenGroup(g.get(), "provenance", where, pobj);
    t.provenance.warnings = h5::ReadAttrStrings(p.get(), "warnings", where, pobj);
    if (h5::LinkExists(p.get(), "sources")) {
      const std::string sobj = pobj + "/sources";
      Handle s = h5::OpenGroup(p.get(), "sources", where, sobj);
      std::vector<std::string> path = h5::ReadStrings(s.get(), "path", where, sobj + "/path");
      std::vector<std::string> sha = h5::ReadStrings(s.get(), "sha256", where, sobj + "/sha256");
      std::vector<std::string> format = h5::ReadStrings(s.get(), "format", where, sobj + "/format");
      if (sha.size() != path.size() || format.size() != path.size()) {
        throw Damaged(where, sobj + ": path, sha256 and format have different lengths");
      }
      for (size_t i = 0; i < path.size(); ++i) {
        t.provenance.sources.push_back({std::move(path[i]), std::move(sha[i]), std::move(format[i])});
      }
    }
  }
  return t;
}

void WriteRootAttributes(hid_t file, const std::string& layout, const Where& where) {
  h5::WriteAttr(file, "format", std::string(kFormatName), where, "/");
  h5::WriteAttr(file, "format_version", int64_t{kCorpusFormatVersion}, where, "/");
  h5::WriteAttr(file, "csw_version", std::string(CSW_VERSION), where, "/");
  h5::WriteAttr(file, "layout", layout, where, "/");
}

Handle CreateHdf5(const std::string& file, const Where& where) {
  Handle fapl = FileAccessList(where);
  return h5::Own(H5Fcreate(file.c_str(), H5F_ACC_EXCL, H5P_DEFAULT, fapl.get()), H5Fclose, where, "cannot create",
                 file);
}

// ---------------------------------------------------------------------------
// Readers: a read lock that other processes' writers see, and the files the
// live Corpus objects of this process reference.

struct ReaderState {
  pid_t pid = 0;
  int fd = -1;  // one fd per corpus and process: closing any fd of a file drops its fcntl locks
  int readers = 0;
  std::map<std::string, int> files;
};

std::mutex& RegistryMutex() {
  static std::mutex m;
  return m;
}

std::map<std::string, ReaderState>& Registry() {
  static auto* r = new std::map<std::string, ReaderState>();
  return *r;
}

std::string RegistryKey(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::absolute(path, ec);
  return (ec ? fs::path(path) : p).lexically_normal().string();
}

std::string ReadersLockPath(const std::string& corpus_path) { return HiddenSibling(corpus_path, ".csw-readers"); }

// Held by every Corpus: a shared fcntl lock on ".<name>.csw-readers" (taken
// before the index is opened) and the list of files its index references.
class ReaderRegistration {
 public:
  explicit ReaderRegistration(const std::string& corpus_path) : key_(RegistryKey(corpus_path)) {
    std::lock_guard<std::mutex> guard(RegistryMutex());
    ReaderState& st = Registry()[key_];
    if (st.pid != ::getpid()) {
      // New, or inherited across fork(): fcntl locks are not inherited.
      if (st.fd >= 0) ::close(st.fd);
      st = ReaderState{};
      st.pid = ::getpid();
    }
    if (st.fd < 0) {
      const std::string lock_path = ReadersLockPath(corpus_path);
      st.fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
      if (st.fd < 0) st.fd = ::open(lock_path.c_str(), O_RDONLY | O_CLOEXEC);  // read-only folder: no writer
      if (st.fd >= 0) {
        struct flock fl {};
        fl.l_type = F_RDLCK;
        fl.l_whence = SEEK_SET;
        ::fcntl(st.fd, F_SETLK, &fl);
      }
    }
    ++st.readers;
  }
  ReaderRegistration(const ReaderRegistration&) = delete;
  ReaderRegistration& operator=(const ReaderRegistration&) = delete;

  void Register(std::vector<std::string> files) {
    std::lock_guard<std::mutex> guard(RegistryMutex());
    ReaderState& st = Registry()[key_];
    for (const std::string& f : files) ++st.files[f];
    files_ = std::move(files);
  }

  ~ReaderRegistration() {
    std::lock_guard<std::mutex> guard(RegistryMutex());
    auto it = Registry().find(key_);
    if (it == Registry().end() || it->second.pid != ::getpid()) return;
    ReaderState& st = it->second;
    for (const std::string& f : files_) {
      auto fi = st.files.find(f);
      if (fi != st.files.end() && --fi->second <= 0) st.files.erase(fi);
    }
    if (--st.readers <= 0) {
      if (st.fd >= 0) ::close(st.fd);
      Registry().erase(it);
    }
  }

 private:
  std::string key_;
  std::vector<std::string> files_;
};

// True when another process holds a Corpus of corpus_path open.
bool OtherProcessReads(const std::string& corpus_path) {
  std::lock_guard<std::mutex> guard(RegistryMutex());
  int fd = -1;
  bool own_fd = false;
  auto it = Registry().find(RegistryKey(corpus_path));
  if (it != Registry().end() && it->second.pid == ::getpid() && it->second.fd >= 0) {
    fd = it->second.fd;
  } else {
    // This process holds no lock on the file, so closing this fd drops none.
    fd = ::open(ReadersLockPath(corpus_path).c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return false;
    own_fd = true;
  }
  struct flock fl {};
  fl.l_type = F_WRLCK;
  fl.l_whence = SEEK_SET;
  const bool busy = ::fcntl(fd, F_GETLK, &fl) != 0 || fl.l_type != F_UNLCK;
  if (own_fd) ::close(fd);
  return busy;
}

// Files referenced by the live Corpus objects of this process.
std::set<std::string> FilesInUseHere(const std::string& corpus_path) {
  std::lock_guard<std::mutex> guard(RegistryMutex());
  std::set<std::string> out;
  auto it = Registry().find(RegistryKey(corpus_path));
  if (it == Registry().end() || it->second.pid != ::getpid()) return out;
  for (const auto& [f, n] : it->second.files) out.insert(f);
  return out;
}

std::function<void(const char*)>& CommitHook() {
  static std::function<void(const char*)> hook;
  return hook;
}

void RunHook(const char* stage) {
  if (CommitHook()) CommitHook()(stage);
}

}  // namespace

namespace corpus_testing {
void SetCommitHook(std::function<void(const char* stage)> hook) { CommitHook() = std::move(hook); }
}  // namespace corpus_testing

// ---------------------------------------------------------------------------
// Corpus

struct Corpus::Impl {
  std::unique_ptr<ReaderRegistration> reader;  // first member: released after the file is closed
  std::string path;
  Where where;
  Handle file;
  int version = 1;
};

Corpus Corpus::Open(const std::string& path) {
  auto lock = h5::Lock();
  auto impl = std::make_shared<Impl>();
  impl->path = path;
  impl->where = {path};
  std::error_code ec;
  if (fs::is_regular_file(path, ec)) impl->reader = std::make_unique<ReaderRegistration>(path);
  impl->file = OpenHdf5(path, H5F_ACC_RDONLY, impl->where);
  std::vector<std::string> files;
  ValidateCorpus(impl->file.get(), impl->where, &files);
  impl->version = static_cast<int>(h5::ReadAttrInt(impl->file.get(), "format_version", impl->where, "/").value_or(1));
  if (impl->reader) impl->reader->Register(std::move(files));
  return Corpus(std::move(impl));
}

std::vector<TakeSummary> Corpus::Takes() const {
  auto lock = h5::Lock();
  Handle takes = h5::OpenGroup(impl_->file.get(), "takes", impl_->where, "/takes");
  std::vector<TakeSummary> out;
  for (const std::string& name : h5::LinkNames(takes.get(), impl_->where, "/takes")) {
    out.push_back(SummarizeTake(impl_->file.get(), name, impl_->where));
  }
  return out;
}

TakeSummary Corpus::Summary(const std::string& take) const {
  auto lock = h5::Lock();
  return SummarizeTake(impl_->file.get(), take, impl_->where);
}

bool Corpus::HasTake(const std::string& name) const {
  if (name.empty() || name.find('/') != std::string::npos) return false;
  auto lock = h5::Lock();
  Handle takes = h5::OpenGroup(impl_->file.get(), "takes", impl_->where, "/takes");
  return h5::LinkExists(takes.get(), name);
}

Take Corpus::LoadTake(const std::string& name) const {
  auto lock = h5::Lock();
  return ReadTake(impl_->file.get(), name, impl_->where);
}

std::string Corpus::TakeMarkerSet(const std::string& take) const {
  auto lock = h5::Lock();
  Handle g = OpenTakeGroup(impl_->file.get(), take, impl_->where);
  return h5::ReadAttrString(g.get(), "markerset", impl_->where, TakeObject(take)).value_or("");
}

std::vector<LabelTier> Corpus::LoadTiers(const std::string& take) const {
  auto lock = h5::Lock();
  Handle g = OpenTakeGroup(impl_->file.get(), take, impl_->where);
  return ReadTiers(g.get(), impl_->where, TakeObject(take));
}

std::vector<std::string> Corpus::ScoreNames(const std::string& take) const {
  auto lock = h5::Lock();
  Handle g = OpenTakeGroup(impl_->file.get(), take, impl_->where);
  if (!h5::LinkExists(g.get(), "scores")) return {};
  const std::string o = TakeObject(take) + "/scores";
  Handle sg = h5::OpenGroup(g.get(), "scores", impl_->where, o);
  return h5::LinkNames(sg.get(), impl_->where, o);
}

std::optional<TakeScores> Corpus::LoadScores(const std::string& take, const std::string& name) const {
  auto lock = h5::Lock();
  Handle g = OpenTakeGroup(impl_->file.get(), take, impl_->where);
  if (BadScoreName(name) || !h5::LinkExists(g.get(), "scores")) return std::nullopt;
  Handle sg = h5::OpenGroup(g.get(), "scores", impl_->where, TakeObject(take) + "/scores");
  if (!h5::LinkExists(sg.get(), name)) return std::nullopt;
  return ReadScoreSet(sg.get(), name, impl_->where, TakeObject(take));
}

int Corpus::format_version() const { return impl_->version; }

MarkerArray Corpus::LoadMarkers(const std::string& take, int64_t first, int64_t count) const {
  auto lock = h5::Lock();
  const std::string obj = TakeObject(take) + "/markers";
  Handle g = OpenTakeGroup(impl_->file.get(), take, impl_->where);
  Handle markers = h5::OpenDataset(g.get(), "markers", impl_->where, obj);
  MarkerShape shape = ShapeOfMarkers(markers.get(), impl_->where, obj);
  if (first < 0 || count < 0 || first > shape.frames || count > shape.frames - first) {
    throw InvalidInput(impl_->path + ": frames [" + std::to_string(first) + ", " + std::to_string(first + count) +
                       ") are outside take '" + take + "' (" + std::to_string(shape.frames) + " frames)");
  }
  MarkerArray out(count, shape.markers);
  ReadMarkerRange(markers.get(), first, count, shape.markers, out.data().data(), impl_->where, obj);
  return out;
}

std::string Corpus::path() const { return impl_->path; }

// ---------------------------------------------------------------------------
// CorpusTransaction

namespace {

// One take of the transaction's table: what the index will say about it.
struct TakeEntry {
  double rate_hz = 0.0;
  int64_t first_frame = 1;
  std::string source_units = "mm";
  std::string imported_utc;
  std::string csw_version;
  std::string markerset;
  int64_t frames = 0;
  int64_t markers = 0;
  int64_t gaps = 0;
  bool has_audio = false;
  int64_t analog_channels = 0;
  std::vector<std::string> tier_names;
  // Files, as the links name them (relative to the corpus folder).
  std::string data_file;
  std::vector<std::string> data_members;  // links into data_file: markers, marker_names, orientations, analog, ...
  std::string tiers_file;
  std::string audio_file;   // empty: no audio group
  std::string scores_file;  // empty: no scores group
  bool writing = false;
};

void WriteTakeAttrs(hid_t g, const TakeEntry& e, const Where& where, const std::string& obj) {
  h5::WriteAttr(g, "rate_hz", e.rate_hz, where, obj);
  h5::WriteAttr(g, "first_frame", e.first_frame, where, obj);
  h5::WriteAttr(g, "source_units", e.source_units, where, obj);
  h5::WriteAttr(g, "imported_utc", e.imported_utc, where, obj);
  h5::WriteAttr(g, "csw_version", e.csw_version, where, obj);
  h5::WriteAttr(g, "markerset", e.markerset, where, obj);
}

void WriteSummaryAttrs(hid_t g, const TakeEntry& e, const Where& where, const std::string& obj) {
  h5::WriteAttr(g, "frame_count", e.frames, where, obj);
  h5::WriteAttr(g, "marker_count", e.markers, where, obj);
  h5::WriteAttr(g, "gap_count", e.gaps, where, obj);
  h5::WriteAttr(g, "has_audio", int64_t{e.has_audio ? 1 : 0}, where, obj);
  h5::WriteAttr(g, "analog_channels", e.analog_channels, where, obj);
  h5::WriteAttr(g, "tier_names", e.tier_names, where, obj);
}

std::string UniqueToken() {
  static std::atomic<uint64_t> counter{0};
  std::random_device rd;
  uint64_t r = (static_cast<uint64_t>(rd()) << 32) ^ rd();
  r ^= static_cast<uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count()) * 0x9E3779B97F4A7C15ull;
  r += (static_cast<uint64_t>(::getpid()) << 40) + counter.fetch_add(1);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(r));
  return buf;
}

constexpr const char* kDataMembers[] = {"markers", "marker_names", "orientations", "analog", "events", "provenance"};

}  // namespace

struct CorpusTransaction::Impl {
  std::unique_ptr<WriterLock> writer_lock;  // first member: released last
  std::string path;
  std::string temp;
  std::string folder_rel;  // "<name>.d"
  std::string folder_abs;
  Where where;
  std::map<std::string, TakeEntry> takes;
  std::set<std::string> created;  // files this transaction made and still owns
  bool copy_reserved = false;     // /models or /dictionaries of the old corpus are not empty
  int open_writers = 0;
  bool committed = false;

  ~Impl() {
    // Without the lock (another writer holds it) nothing here is ours.
    if (!committed && writer_lock) {
      for (const std::string& f : created) ::unlink(Abs(f).c_str());
      ::unlink(temp.c_str());
    }
  }

  std::string Abs(const std::string& rel) const { return InCorpusDir(path, rel); }

  void CheckUsable() const {
    if (committed) throw Error(path + ": the transaction was already committed");
  }

  const TakeEntry& Entry(const std::string& name) const {
    auto it = takes.find(name);
    if (name.empty() || name.find('/') != std::string::npos || it == takes.end()) {
      throw InvalidInput(path + ": no take named '" + name + "'");
    }
    return it->second;
  }
  TakeEntry& Entry(const std::string& name) { return const_cast<TakeEntry&>(std::as_const(*this).Entry(name)); }

  // Creates a new, uniquely named HDF5 file in the folder, owned by the transaction.
  Handle NewFile(const std::string& take, const std::string& suffix, const std::string& format, std::string* rel) {
    std::error_code ec;
    if (!fs::is_directory(folder_abs, ec)) {
      fs::create_directories(folder_abs, ec);
      if (ec) throw IoError(path, "cannot create the folder " + folder_abs + ": " + ec.message());
      fs::path dir = fs::path(folder_abs).parent_path();
      FsyncPath(dir.empty() ? std::string(".") : dir.string(), true, path);
    }
    std::string safe;
    for (unsigned char c : take) safe += (std::isalnum(c) != 0 || c == '-' || c == '_') ? static_cast<char>(c) : '_';
    if (safe.size() > 40) safe.resize(40);
    *rel = folder_rel + "/" + safe + "-" + UniqueToken() + suffix;
    Handle f = CreateHdf5(Abs(*rel), where);
    created.insert(*rel);
    h5::WriteAttr(f.get(), "format", format, where, *rel);
    h5::WriteAttr(f.get(), "take", take, where, *rel);
    return f;
  }

  static void Close(Handle* f, const std::string& path, const std::string& rel) {
    if (!f->Reset()) throw IoError(path, "cannot close " + rel + ": " + h5::TakeErrorMessage());
  }

  // Deletes a file of this transaction that nothing will reference.
  void Discard(const std::string& rel) {
    if (!rel.empty() && created.erase(rel) > 0) ::unlink(Abs(rel).c_str());
  }
  void DiscardEntry(const TakeEntry& e) {
    Discard(e.data_file);
    Discard(e.tiers_file);
    Discard(e.audio_file);
    Discard(e.scores_file);
  }

  std::string WriteTiersFile(const std::string& take, const std::vector<LabelTier>& tiers) {
    std::string rel;
    Handle f = NewFile(take, ".tiers.h5", "csw-take-tiers", &rel);
    WriteTierGroups(f.get(), tiers, where, TakeObject(take));
    Close(&f, path, rel);
    return rel;
  }

  std::string WriteAudioFile(const std::string& take, const Audio& audio, const std::string& source_path) {
    if (audio.samples.empty() && source_path.empty()) return "";
    std::string rel;
    Handle f = NewFile(take, ".audio.h5", "csw-take-audio", &rel);
    WriteAudioGroup(f.get(), audio, source_path, where, TakeObject(take));
    Close(&f, path, rel);
    return rel;
  }

  std::set<std::string> Referenced() const {
    std::set<std::string> out;
    for (const auto& [name, e] : takes) {
      for (const std::string* f : {&e.data_file, &e.tiers_file, &e.audio_file, &e.scores_file}) {
        if (!f->empty()) out.insert(*f);
      }
    }
    return out;
  }

  void Load(Progress* progress);
  void Extract(hid_t file, hid_t takes_group, const std::string& name, TakeEntry* e);
  void WriteIndex();
  void CollectGarbage(const std::set<std::string>& keep);
};

void CorpusTransaction::Impl::Extract(hid_t file, hid_t takes_group, const std::string& name, TakeEntry* e) {
  const std::string obj = TakeObject(name);
  TakeSummary s = SummarizeTake(file, name, where);
  e->frames = s.frames;
  e->markers = s.markers;
  e->gaps = s.gaps;
  e->has_audio = s.has_audio;
  e->analog_channels = s.analog_channels;
  e->tier_names = s.tier_names;
  Handle g = h5::OpenGroup(takes_group, name, where, obj);
  {
    Handle f = NewFile(name, ".h5", "csw-take", &e->data_file);
    WriteTakeAttrs(f.get(), *e, where, e->data_file);
    for (const char* member : kDataMembers) {
      if (!h5::LinkExists(g.get(), member)) continue;
      h5::CopyTree(g.get(), member, f.get(), where, obj + "/" + member);
      e->data_members.push_back(member);
    }
    Handle markers = h5::OpenDataset(f.get(), "markers", where, obj + "/markers");
    h5::WriteAttr(markers.get(), "gaps", e->gaps, where, obj + "/markers");
    markers.Reset();
    Close(&f, path, e->data_file);
  }
  {
    Handle f = NewFile(name, ".tiers.h5", "csw-take-tiers", &e->tiers_file);
    if (h5::LinkExists(g.get(), "tiers")) {
      h5::CopyTree(g.get(), "tiers", f.get(), where, obj + "/tiers");
    } else {
      WriteTierGroups(f.get(), {}, where, obj);
    }
    Close(&f, path, e->tiers_file);
  }
  if (h5::LinkExists(g.get(), "audio")) {
    Handle f = NewFile(name, ".audio.h5", "csw-take-audio", &e->audio_file);
    h5::CopyTree(g.get(), "audio", f.get(), where, obj + "/audio");
    Close(&f, path, e->audio_file);
  }
  if (h5::LinkExists(g.get(), "scores")) {
    Handle f = NewFile(name, ".scores.h5", "csw-take-scores", &e->scores_file);
    h5::CopyTree(g.get(), "scores", f.get(), where, obj + "/scores");
    Close(&f, path, e->scores_file);
  }
}

void CorpusTransaction::Impl::Load(Progress* progress) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return;
  Corpus::Open(path);  // refuse to replace anything that is not a valid corpus
  Handle file = OpenHdf5(path, H5F_ACC_RDONLY, where);
  Handle tg = h5::OpenGroup(file.get(), "takes", where, "/takes");
  const std::vector<std::string> names = h5::LinkNames(tg.get(), where, "/takes");
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string& name = names[i];
    const std::string obj = TakeObject(name);
    if (progress != nullptr) progress->Update("reading the corpus", static_cast<double>(i) / names.size());
    TakeEntry e;
    Handle g = h5::OpenGroup(tg.get(), name, where, obj);
    e.rate_hz = h5::ReadAttrDouble(g.get(), "rate_hz", where, obj).value_or(0.0);
    e.first_frame = h5::ReadAttrInt(g.get(), "first_frame", where, obj).value_or(1);
    e.source_units = h5::ReadAttrString(g.get(), "source_units", where, obj).value_or("mm");
    e.imported_utc = h5::ReadAttrString(g.get(), "imported_utc", where, obj).value_or("");
    e.csw_version = h5::ReadAttrString(g.get(), "csw_version", where, obj).value_or("");
    e.markerset = h5::ReadAttrString(g.get(), "markerset", where, obj).value_or("");
    // A take already split into files (every member an external link into its
    // files) is kept as it is; any other (version 1, packed, edited by another
    // tool) is copied into new files.
    LinkTarget markers = LinkTargetOf(g.get(), "markers");
    bool linked = markers.external;
    for (const char* member : kDataMembers) {
      if (!h5::LinkExists(g.get(), member)) continue;
      LinkTarget t = LinkTargetOf(g.get(), member);
      linked = linked && t.external && t.file == markers.file && t.object == std::string("/") + member;
      e.data_members.push_back(member);
    }
    LinkTarget tiers = LinkTargetOf(g.get(), "tiers");
    linked = linked && tiers.external && tiers.object == "/tiers";
    LinkTarget audio;
    if (h5::LinkExists(g.get(), "audio")) {
      audio = LinkTargetOf(g.get(), "audio");
      linked = linked && audio.external && audio.object == "/audio";
    }
    LinkTarget scores;
    if (h5::LinkExists(g.get(), "scores")) {
      scores = LinkTargetOf(g.get(), "scores");
      linked = linked && scores.external && scores.object == "/scores";
    }
    if (linked) {
      TakeSummary s = SummarizeTake(file.get(), name, where);
      e.frames = s.frames;
      e.markers = s.markers;
      e.gaps = s.gaps;
      e.has_audio = s.has_audio;
      e.analog_channels = s.analog_channels;
      e.tier_names = s.tier_names;
      e.data_file = markers.file;
      e.tiers_file = tiers.file;
      e.audio_file = audio.file;
      e.scores_file = scores.file;
    } else {
      e.data_members.clear();
      Extract(file.get(), tg.get(), name, &e);
    }
    takes.emplace(name, std::move(e));
  }
  for (const char* reserved : {"models", "dictionaries"}) {
    if (!h5::LinkExists(file.get(), reserved)) continue;
    Handle r = h5::OpenGroup(file.get(), reserved, where, std::string("/") + reserved);
    if (!h5::LinkNames(r.get(), where, std::string("/") + reserved).empty()) copy_reserved = true;
  }
  if (progress != nullptr) progress->Update("reading the corpus", 1.0);
}

void CorpusTransaction::Impl::WriteIndex() {
  ::unlink(temp.c_str());
  Handle f = CreateHdf5(temp, where);
  WriteRootAttributes(f.get(), "index", where);
  Handle tg = h5::CreateGroup(f.get(), "takes", where, "/takes");
  for (const auto& [name, e] : takes) {
    const std::string obj = TakeObject(name);
    Handle g = h5::CreateGroup(tg.get(), name, where, obj);
    WriteTakeAttrs(g.get(), e, where, obj);
    WriteSummaryAttrs(g.get(), e, where, obj);
    auto link = [&](const std::string& file, const std::string& member) {
      h5::Check(
          H5Lcreate_external(file.c_str(), ("/" + member).c_str(), g.get(), member.c_str(), H5P_DEFAULT, H5P_DEFAULT),
          where, "cannot link", obj + "/" + member);
    };
    for (const std::string& member : e.data_members) link(e.data_file, member);
    link(e.tiers_file, "tiers");
    if (!e.audio_file.empty()) link(e.audio_file, "audio");
    if (!e.scores_file.empty()) link(e.scores_file, "scores");
  }
  Handle old;
  if (copy_reserved) old = OpenHdf5(path, H5F_ACC_RDONLY, where);
  for (const char* reserved : {"models", "dictionaries"}) {
    if (old.valid() && h5::LinkExists(old.get(), reserved)) {
      h5::CopyTree(old.get(), reserved, f.get(), where, std::string("/") + reserved);
    } else {
      h5::CreateGroup(f.get(), reserved, where, std::string("/") + reserved);
    }
  }
  old.Reset();
  tg.Reset();
  h5::Check(H5Fflush(f.get(), H5F_SCOPE_GLOBAL), where, "cannot flush", temp);
  Close(&f, path, temp);
}

// Deletes the files of the folder that `keep` does not name, unless a reader
// may still need them: nothing while another process holds a Corpus open,
// and never a file a live Corpus of this process references. What is left is
// deleted by a later transaction.
void CorpusTransaction::Impl::CollectGarbage(const std::set<std::string>& keep) {
  std::error_code ec;
  if (!fs::is_directory(folder_abs, ec)) return;
  if (OtherProcessReads(path)) return;
  const std::set<std::string> in_use = FilesInUseHere(path);
  std::vector<fs::path> doomed;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder_abs, ec)) {
    const std::string rel = folder_rel + "/" + entry.path().filename().string();
    if (keep.count(rel) == 0 && created.count(rel) == 0 && in_use.count(rel) == 0) doomed.push_back(entry.path());
  }
  for (const fs::path& p : doomed) fs::remove(p, ec);
}

std::string CorpusTransaction::TempPath(const std::string& corpus_path) {
  return HiddenSibling(corpus_path, ".csw-tmp");
}

std::string CorpusTransaction::FolderPath(const std::string& corpus_path) { return corpus_path + ".d"; }

CorpusTransaction::CorpusTransaction(const std::string& path) : impl_(std::make_unique<Impl>()) {
  auto lock = h5::Lock();
  Impl& t = *impl_;
  t.path = path;
  t.where = {path};
  t.temp = TempPath(path);
  t.folder_abs = FolderPath(path);
  t.folder_rel = fs::path(path).filename().string() + ".d";
  t.writer_lock = std::make_unique<WriterLock>(path, "corpus");
  // We hold the lock: a temporary index left here belongs to a killed writer.
  std::error_code ec;
  fs::remove(t.temp, ec);
  fs::remove(t.temp + ".compact", ec);  // left by csw before format version 2
  t.Load(nullptr);
  t.CollectGarbage(t.Referenced());  // files of a killed writer, old generations no reader needs
}

CorpusTransaction::CorpusTransaction(const std::string& path, Progress& progress) : impl_(std::make_unique<Impl>()) {
  auto lock = h5::Lock();
  Impl& t = *impl_;
  t.path = path;
  t.where = {path};
  t.temp = TempPath(path);
  t.folder_abs = FolderPath(path);
  t.folder_rel = fs::path(path).filename().string() + ".d";
  t.writer_lock = std::make_unique<WriterLock>(path, "corpus");
  std::error_code ec;
  fs::remove(t.temp, ec);
  fs::remove(t.temp + ".compact", ec);
  t.Load(&progress);
  t.CollectGarbage(t.Referenced());
}

CorpusTransaction::~CorpusTransaction() {
  auto lock = h5::Lock();
  impl_.reset();
}

const std::string& CorpusTransaction::path() const { return impl_->path; }

bool CorpusTransaction::HasTake(const std::string& name) const {
  auto lock = h5::Lock();
  impl_->CheckUsable();
  return impl_->takes.count(name) > 0;
}

std::vector<std::string> CorpusTransaction::TakeNames() const {
  auto lock = h5::Lock();
  impl_->CheckUsable();
  std::vector<std::string> out;
  for (const auto& [name, e] : impl_->takes) out.push_back(name);
  return out;
}

void CorpusTransaction::RemoveTake(const std::string& name) {
  auto lock = h5::Lock();
  impl_->CheckUsable();
  TakeEntry& e = impl_->Entry(name);
  if (e.writing) throw Error(impl_->path + ": take '" + name + "' is still being written");
  impl_->DiscardEntry(e);
  impl_->takes.erase(name);
}

std::vector<LabelTier> CorpusTransaction::LoadTiers(const std::string& take) const {
  auto lock = h5::Lock();
  impl_->CheckUsable();
  const TakeEntry& e = impl_->Entry(take);
  if (e.tiers_file.empty()) return {};
  Handle f = OpenHdf5(impl_->Abs(e.tiers_file), H5F_ACC_RDONLY, Where{impl_->Abs(e.tiers_file)});
  return ReadTiers(f.get(), Where{impl_->Abs(e.tiers_file)}, TakeObject(take));
}

void CorpusTransaction::WriteTiers(const std::string& take, const std::vector<LabelTier>& tiers) {
  auto lock = h5::Lock();
  impl_->CheckUsable();
  TakeEntry& e = impl_->Entry(take);
  std::string rel = impl_->WriteTiersFile(take, tiers);
  impl_->Discard(e.tiers_file);
  e.tiers_file = rel;
  e.tier_names.clear();
  for (const LabelTier& t : tiers) e.tier_names.push_back(t.name);
}

std::string ScoresProblem(const TakeScores& s) {
  if (BadScoreName(s.name)) return "score set name '" + s.name + "' must be non-empty, without '/', not . or ..";
  if (!(s.rate_hz > 0) || !std::isfinite(s.rate_hz)) return "score set '" + s.name + "': rate_hz must be > 0";
  if (!std::isfinite(s.start_s)) return "score set '" + s.name + "': start_s must be finite";
  std::set<std::string> seen;
  for (const ScoreMatrix& m : s.matrices) {
    const std::string w = "score set '" + s.name + "': matrix '" + m.name + "'";
    if (BadScoreName(m.name)) return w + ": the name must be non-empty, without '/', not . or ..";
    if (!seen.insert(m.name).second) return w + " appears twice";
    if (m.rows < 0 || m.cols < 0 || static_cast<double>(m.values.size()) != static_cast<double>(m.rows) * m.cols)
      return w + ": " + std::to_string(m.values.size()) + " values for " + std::to_string(m.rows) + " × " +
             std::to_string(m.cols);
    if (!m.column_names.empty() && static_cast<int64_t>(m.column_names.size()) != m.cols)
      return w + ": " + std::to_string(m.column_names.size()) + " column names for " + std::to_string(m.cols) +
             " columns";
  }
  return "";
}

void CorpusTransaction::WriteScores(const std::string& take, const TakeScores& scores) {
  if (const std::string why = ScoresProblem(scores); !why.empty())
    throw InvalidInput(impl_->path + ": take '" + take + "': " + why);
  auto lock = h5::Lock();
  impl_->CheckUsable();
  TakeEntry& e = impl_->Entry(take);
  const std::string obj = TakeObject(take);
  std::string rel;
  Handle f = impl_->NewFile(take, ".scores.h5", "csw-take-scores", &rel);
  {
    Handle sg = h5::CreateGroup(f.get(), "scores", impl_->where, obj + "/scores");
    if (!e.scores_file.empty()) {  // keep the take's other sets
      Handle old = OpenHdf5(impl_->Abs(e.scores_file), H5F_ACC_RDONLY, impl_->where);
      Handle og = h5::OpenGroup(old.get(), "scores", impl_->where, obj + "/scores");
      for (const std::string& n : h5::LinkNames(og.get(), impl_->where, obj + "/scores"))
        if (n != scores.name) h5::CopyTree(og.get(), n, sg.get(), impl_->where, obj + "/scores/" + n);
    }
    WriteScoreSet(sg.get(), scores, impl_->where, obj);
  }
  Impl::Close(&f, impl_->path, rel);
  impl_->Discard(e.scores_file);
  e.scores_file = rel;
}

void CorpusTransaction::WriteAudio(const std::string& take, const Audio& audio, const std::string& source_path) {
  CheckAudio(audio);
  auto lock = h5::Lock();
  impl_->CheckUsable();
  TakeEntry& e = impl_->Entry(take);
  std::string rel = impl_->WriteAudioFile(take, audio, source_path);
  impl_->Discard(e.audio_file);
  e.audio_file = rel;
  e.has_audio = audio.frames() > 0;
}

void CorpusTransaction::Commit() {
  auto lock = h5::Lock();
  Impl& t = *impl_;
  t.CheckUsable();
  if (t.open_writers > 0) throw Error(t.path + ": cannot commit while a take is still being written (call Finish)");
  // (1) The new take files are durable before any index names them.
  const std::set<std::string> referenced = t.Referenced();
  for (auto it = t.created.begin(); it != t.created.end();) {
    if (referenced.count(*it) == 0) {
      ::unlink(t.Abs(*it).c_str());
      it = t.created.erase(it);
    } else {
      FsyncPath(t.Abs(*it), false, t.path);
      ++it;
    }
  }
  if (!t.created.empty()) FsyncPath(t.folder_abs, true, t.path);
  RunHook("take files synced");
  // (2) A fresh index from the table, atomically replacing the corpus.
  t.WriteIndex();
  RunHook("index written");
  try {
    ReplaceFileDurably(t.temp, t.path);
  } catch (...) {
    std::error_code ec;
    if (!fs::exists(t.temp, ec)) {  // renamed: the new files are the corpus' now
      t.committed = true;
      t.created.clear();
    }
    throw;
  }
  t.committed = true;
  t.created.clear();
  RunHook("index replaced");
  // (3) Garbage: files no index references any more, unless a reader may need them.
  try {
    t.CollectGarbage(referenced);
  } catch (const std::exception&) {
    // Left for a later transaction.
  }
}

// ---------------------------------------------------------------------------
// TakeWriter

struct CorpusTransaction::TakeWriter::Impl {
  CorpusTransaction::Impl* tx = nullptr;
  std::string name;
  std::string object;
  Handle file;            // the take's new data file
  std::string data_file;  // its name, as the index links it
  Handle markers;
  Handle analog;
  Handle orientations;  // only for a take with a skeleton
  int64_t joints = 0;   // skeleton joints (= marker_count) when orientations are written
  int64_t orientation_frames = 0;
  int64_t marker_count = 0;
  int64_t analog_channels = 0;
  int64_t analog_samples = 0;
  int64_t chunk_frames = kCorpusChunkFrames;
  // Frames are gathered into a batch of a few chunks, which are deflated in
  // parallel (one compressor per thread) and then stored in order.
  int threads = 1;
  int64_t batch_chunks = 1;
  std::vector<float> buffer;  // batch_chunks * chunk_frames frames
  int64_t buffered = 0;
  int64_t flushed = 0;
  std::vector<uint8_t> in_gap;
  int64_t gaps = 0;
  bool finished = false;
  std::vector<std::unique_ptr<libdeflate_compressor, CompressorDeleter>> compressors;  // per thread
  std::vector<std::vector<uint8_t>> shuffled;                                          // per thread
  std::vector<std::vector<uint8_t>> compressed;                                        // per chunk
  std::vector<size_t> compressed_size;                                                 // per chunk

  void CheckOpen() const {
    if (finished) throw Error(tx->path + ": take '" + name + "' was already finished");
    tx->CheckUsable();
  }

  // An unfinished writer removes its partial take and its files, so that the
  // transaction never commits half a take.
  ~Impl() {
    if (finished || tx == nullptr) return;
    auto lock = h5::Lock();
    analog.Reset();
    orientations.Reset();
    markers.Reset();
    file.Reset();
    H5Eclear2(H5E_DEFAULT);
    --tx->open_writers;
    if (!tx->committed) {
      auto it = tx->takes.find(name);
      if (it != tx->takes.end() && it->second.data_file == data_file) {
        tx->DiscardEntry(it->second);
        tx->takes.erase(it);
      }
      tx->Discard(data_file);
    }
  }

  int64_t row() const { return marker_count * 3; }
  int64_t batch_frames() const { return batch_chunks * chunk_frames; }

  void Allocate() {
    if (!buffer.empty() || marker_count == 0) return;
    const size_t chunk_bytes = static_cast<size_t>(chunk_frames * row()) * sizeof(float);
    buffer.resize(static_cast<size_t>(batch_frames() * row()));
    for (int t = 0; t < threads; ++t) {
      compressors.emplace_back(libdeflate_alloc_compressor(kCorpusDeflateLevel));
      if (!compressors.back()) throw Error("out of memory allocating a deflate compressor");
      shuffled.emplace_back(chunk_bytes);
    }
    const size_t bound = libdeflate_zlib_compress_bound(compressors[0].get(), chunk_bytes);
    compressed.assign(static_cast<size_t>(batch_chunks), std::vector<uint8_t>(bound));
    compressed_size.assign(static_cast<size_t>(batch_chunks), 0);
  }

  void Release() {
    std::vector<float>().swap(buffer);
    compressors.clear();
    shuffled.clear();
    compressed.clear();
    compressed_size.clear();
  }

  // Writes the `buffered` frames of the batch, starting at `flushed` (a chunk
  // boundary). Each chunk is shuffled and deflated here (libdeflate, zlib
  // format: exactly what HDF5's shuffle + deflate filters produce and read)
  // and stored with H5Dwrite_chunk; a last partial chunk is padded with NaN.
  void FlushBatch() {
    if (buffered == 0) return;
    const std::string obj = object + "/markers";
    const int64_t frames = buffered;
    hsize_t dims[3] = {static_cast<hsize_t>(flushed + frames), static_cast<hsize_t>(marker_count), 3};
    h5::Check(H5Dset_extent(markers.get(), dims), tx->where, "cannot extend", obj);
    if (marker_count == 0) {
      flushed += frames;
      buffered = 0;
      return;
    }
    if constexpr (std::endian::native != std::endian::little) {
      WriteThroughHdf5(frames, obj);
      return;
    }
    const int64_t chunks = (frames + chunk_frames - 1) / chunk_frames;
    const size_t chunk_values = static_cast<size_t>(chunk_frames * row());
    std::fill(buffer.begin() + frames * row(), buffer.begin() + chunks * chunk_frames * row(), kMissing);
    std::atomic<bool> failed{false};
    auto work = [&](int t) {
      for (int64_t c = t; c < chunks; c += threads) {
        Shuffle4(buffer.data() + static_cast<size_t>(c) * chunk_values, chunk_values, shuffled[t].data());
        auto& out = compressed[static_cast<size_t>(c)];
        size_t size = libdeflate_zlib_compress(compressors[t].get(), shuffled[t].data(), shuffled[t].size(), out.data(),
                                               out.size());
        if (size == 0) failed = true;
        compressed_size[static_cast<size_t>(c)] = size;
      }
    };
    const int helpers = static_cast<int>(std::min<int64_t>(threads, chunks)) - 1;
    std::vector<std::thread> pool;
    for (int t = 1; t <= helpers; ++t) pool.emplace_back(work, t);
    work(0);
    for (auto& th : pool) th.join();
    if (helpers + 1 < threads) {
      // Chunks assigned to threads that were not started.
      for (int t = helpers + 1; t < threads; ++t) work(t);
    }
    if (failed) throw Error(tx->path + ": deflate failed on a chunk of " + obj);
    for (int64_t c = 0; c < chunks; ++c) {
      hsize_t offset[3] = {static_cast<hsize_t>(flushed + c * chunk_frames), 0, 0};
      h5::Check(H5Dwrite_chunk(markers.get(), H5P_DEFAULT, 0, offset, compressed_size[static_cast<size_t>(c)],
                               compressed[static_cast<size_t>(c)].data()),
                tx->where, "cannot write a chunk of", obj);
    }
    flushed += frames;
    buffered = 0;
  }

  // Portable path (big-endian hosts): let HDF5 run its own filters.
  void WriteThroughHdf5(int64_t frames, const std::string& obj) {
    Handle fspace = h5::Own(H5Dget_space(markers.get()), H5Sclose, tx->where, "cannot write", obj);
    hsize_t start[3] = {static_cast<hsize_t>(flushed), 0, 0};
    hsize_t cnt[3] = {static_cast<hsize_t>(frames), static_cast<hsize_t>(marker_count), 3};
    h5::Check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, cnt, nullptr), tx->where,
              "cannot select", obj);
    Handle mspace = h5::Own(H5Screate_simple(3, cnt, nullptr), H5Sclose, tx->where, "cannot write", obj);
    h5::Check(H5Dwrite(markers.get(), H5T_NATIVE_FLOAT, mspace.get(), fspace.get(), H5P_DEFAULT, buffer.data()),
              tx->where, "cannot write", obj);
    flushed += frames;
    buffered = 0;
  }
};

CorpusTransaction::TakeWriter::TakeWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
CorpusTransaction::TakeWriter::TakeWriter(TakeWriter&&) noexcept = default;
CorpusTransaction::TakeWriter& CorpusTransaction::TakeWriter::operator=(TakeWriter&&) noexcept = default;

CorpusTransaction::TakeWriter::~TakeWriter() = default;

int64_t CorpusTransaction::TakeWriter::frames_written() const { return impl_->flushed + impl_->buffered; }

void CorpusTransaction::TakeWriter::AppendFrames(const float* xyz_mm, int64_t frames) {
  auto lock = h5::Lock();
  Impl& w = *impl_;
  w.CheckOpen();
  if (frames < 0) throw InvalidInput("AppendFrames: negative frame count");
  if (frames == 0) return;
  if (xyz_mm == nullptr && w.marker_count > 0) throw InvalidInput("AppendFrames: no data");
  const int64_t row = w.row();
  for (int64_t f = 0; f < frames; ++f) {
    for (int64_t m = 0; m < w.marker_count; ++m) {
      bool missing = std::isnan(xyz_mm[f * row + m * 3]);
      if (missing && !w.in_gap[static_cast<size_t>(m)]) ++w.gaps;
      w.in_gap[static_cast<size_t>(m)] = missing;
    }
  }
  w.Allocate();
  int64_t done = 0;
  while (done < frames) {
    int64_t take = std::min(frames - done, w.batch_frames() - w.buffered);
    if (row > 0) std::copy(xyz_mm + done * row, xyz_mm + (done + take) * row, w.buffer.begin() + w.buffered * row);
    w.buffered += take;
    done += take;
    if (w.buffered == w.batch_frames()) w.FlushBatch();
  }
}

void CorpusTransaction::TakeWriter::AppendAnalog(const float* values, int64_t samples) {
  auto lock = h5::Lock();
  Impl& w = *impl_;
  w.CheckOpen();
  if (samples < 0) throw InvalidInput("AppendAnalog: negative sample count");
  if (samples == 0) return;
  if (w.analog_channels == 0) throw InvalidInput("take '" + w.name + "' was begun without analog channels");
  if (values == nullptr) throw InvalidInput("AppendAnalog: no data");
  Append2D(w.analog.get(), w.analog_samples, samples, w.analog_channels, values, w.tx->where,
           w.object + "/analog/data");
  w.analog_samples += samples;
}

void CorpusTransaction::TakeWriter::AppendOrientations(const float* wxyz, int64_t frames) {
  auto lock = h5::Lock();
  Impl& w = *impl_;
  w.CheckOpen();
  if (frames < 0) throw InvalidInput("AppendOrientations: negative frame count");
  if (frames == 0) return;
  if (!w.orientations.valid()) throw InvalidInput("take '" + w.name + "' was begun without a skeleton");
  if (wxyz == nullptr && w.joints > 0) throw InvalidInput("AppendOrientations: no data");
  AppendOrientationFrames(w.orientations.get(), w.orientation_frames, frames, w.joints, wxyz, w.tx->where,
                          w.object + "/orientations");
  w.orientation_frames += frames;
}

void CorpusTransaction::TakeWriter::Finish() {
  auto lock = h5::Lock();
  Impl& w = *impl_;
  w.CheckOpen();
  if (w.orientations.valid() && w.orientation_frames != w.flushed + w.buffered) {
    throw InvalidInput("take '" + w.name + "': orientations for " + std::to_string(w.orientation_frames) +
                       " frames but markers for " + std::to_string(w.flushed + w.buffered) + " frames");
  }
  w.FlushBatch();
  h5::WriteAttr(w.markers.get(), "gaps", w.gaps, w.tx->where, w.object + "/markers");
  w.Release();
  w.analog.Reset();
  w.orientations.Reset();
  w.markers.Reset();
  h5::Check(H5Fflush(w.file.get(), H5F_SCOPE_GLOBAL), w.tx->where, "cannot flush", w.data_file);
  CorpusTransaction::Impl::Close(&w.file, w.tx->path, w.data_file);
  auto it = w.tx->takes.find(w.name);
  if (it != w.tx->takes.end() && it->second.data_file == w.data_file) {
    it->second.frames = w.flushed;
    it->second.gaps = w.gaps;
    it->second.writing = false;
  }
  w.finished = true;
  --w.tx->open_writers;
}

CorpusTransaction::TakeWriter CorpusTransaction::BeginTake(const Take& h, IfTakeExists if_exists) {
  ValidateTakeName(h.name);
  const int64_t marker_count = static_cast<int64_t>(h.marker_names.size());
  const int64_t channels = h.analog.channels();
  if (h.analog.samples < 0 || h.analog.data.size() != static_cast<size_t>(h.analog.samples * channels)) {
    throw InvalidInput("take '" + h.name + "': analog data has " + std::to_string(h.analog.data.size()) +
                       " values, expected samples × channels = " + std::to_string(h.analog.samples) + " × " +
                       std::to_string(channels));
  }
  CheckAudio(h.audio);
  const int64_t joints = static_cast<int64_t>(h.skeleton.size());
  if (joints > 0 && joints != marker_count) {
    throw InvalidInput("take '" + h.name + "': a skeleton of " + std::to_string(joints) + " joints for " +
                       std::to_string(marker_count) + " markers (joint j must be marker j)");
  }
  if (joints == 0 && !h.orientations.empty()) {
    throw InvalidInput("take '" + h.name + "' has orientations but no skeleton");
  }
  if (!h.orientations.empty() && h.orientations.joints() != joints) {
    throw InvalidInput("take '" + h.name + "': orientations of " + std::to_string(h.orientations.joints()) +
                       " joints for a skeleton of " + std::to_string(joints));
  }
  for (int64_t j = 0; j < joints; ++j) {
    const int parent = h.skeleton[static_cast<size_t>(j)].parent;
    if (parent < -1 || parent >= j) {
      throw InvalidInput("take '" + h.name + "': skeleton joint '" + h.skeleton[static_cast<size_t>(j)].name +
                         "' has parent " + std::to_string(parent) + " (parents must come first)");
    }
  }
  auto lock = h5::Lock();
  Impl& t = *impl_;
  t.CheckUsable();
  const Where& where = t.where;
  const std::string obj = TakeObject(h.name);
  if (auto it = t.takes.find(h.name); it != t.takes.end()) {
    if (if_exists == IfTakeExists::kFail) throw InvalidInput(t.path + ": a take named '" + h.name + "' already exists");
    if (it->second.writing) throw Error(t.path + ": take '" + h.name + "' is still being written");
    t.DiscardEntry(it->second);
    t.takes.erase(it);
  }
  const std::string csw_version = h.provenance.csw_version.empty() ? CSW_VERSION : h.provenance.csw_version;
  const std::string imported_utc = h.provenance.imported_utc.empty() ? UtcNow() : h.provenance.imported_utc;
  TakeEntry& e = t.takes[h.name];
  e.rate_hz = h.rate_hz;
  e.first_frame = h.first_frame;
  e.source_units = h.source_units;
  e.imported_utc = imported_utc;
  e.csw_version = csw_version;
  e.markerset = h.markerset_json;
  e.markers = marker_count;
  e.has_audio = h.audio.frames() > 0;
  e.analog_channels = channels;
  for (const LabelTier& tier : h.tiers) e.tier_names.push_back(tier.name);
  e.data_members = {"markers", "marker_names"};
  if (joints > 0) e.data_members.push_back("orientations");
  if (channels > 0) e.data_members.push_back("analog");
  e.data_members.push_back("events");
  e.data_members.push_back("provenance");
  e.writing = true;

  auto w = std::make_unique<TakeWriter::Impl>();
  w->tx = &t;
  w->name = h.name;
  w->object = obj;
  w->marker_count = marker_count;
  w->analog_channels = channels;
  w->in_gap.assign(static_cast<size_t>(marker_count), 0);
  w->threads = static_cast<int>(std::clamp<unsigned>(std::thread::hardware_concurrency(), 1, 4));
  w->batch_chunks = 2 * w->threads;
  ++t.open_writers;
  TakeWriter writer(std::move(w));  // from here on, a failure removes the partial take and its files
  TakeWriter::Impl& wi = *writer.impl_;
  wi.file = t.NewFile(h.name, ".h5", "csw-take", &wi.data_file);
  e.data_file = wi.data_file;
  e.tiers_file = t.WriteTiersFile(h.name, h.tiers);
  e.audio_file = t.WriteAudioFile(h.name, h.audio, h.audio_path);
  hid_t g = wi.file.get();
  WriteTakeAttrs(g, e, where, obj);
  h5::WriteStrings(g, "marker_names", h.marker_names, where, obj + "/marker_names");
  {
    const std::string mobj = obj + "/markers";
    // With no markers the marker dimension must be extendible for a valid chunk shape.
    hsize_t dims[3] = {0, static_cast<hsize_t>(marker_count), 3};
    hsize_t maxdims[3] = {H5S_UNLIMITED, marker_count > 0 ? static_cast<hsize_t>(marker_count) : H5S_UNLIMITED, 3};
    hsize_t chunk[3] = {static_cast<hsize_t>(wi.chunk_frames), static_cast<hsize_t>(std::max<int64_t>(1, marker_count)),
                        3};
    Handle space = h5::Own(H5Screate_simple(3, dims, maxdims), H5Sclose, where, "cannot create", mobj);
    Handle dcpl = h5::Own(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, where, "cannot create", mobj);
    h5::Check(H5Pset_chunk(dcpl.get(), 3, chunk), where, "cannot chunk", mobj);
    h5::Check(H5Pset_shuffle(dcpl.get()), where, "cannot set the shuffle filter of", mobj);
    h5::Check(H5Pset_deflate(dcpl.get(), kCorpusDeflateLevel), where, "cannot set the deflate filter of", mobj);
    float fill = kMissing;
    h5::Check(H5Pset_fill_value(dcpl.get(), H5T_NATIVE_FLOAT, &fill), where, "cannot set the fill value of", mobj);
    wi.markers = h5::Own(H5Dcreate2(g, "markers", H5T_IEEE_F32LE, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                         H5Dclose, where, "cannot create", mobj);
    h5::WriteAttr(wi.markers.get(), "units", std::string("mm"), where, mobj);
  }
  if (channels > 0) {
    const std::string aobj = obj + "/analog";
    Handle a = h5::CreateGroup(g, "analog", where, aobj);
    h5::WriteStrings(a.get(), "names", h.analog.names, where, aobj + "/names");
    h5::WriteStrings(a.get(), "units", PadTo(h.analog.units, h.analog.names.size()), where, aobj + "/units");
    h5::WriteStrings(a.get(), "descriptions", PadTo(h.analog.descriptions, h.analog.names.size()), where,
                     aobj + "/descriptions");
    wi.analog = CreateExtendible2D(a.get(), "data", channels, std::max<int64_t>(1, kAnalogChunkBytes / (4 * channels)),
                                   where, aobj + "/data");
    h5::WriteAttr(wi.analog.get(), "rate_hz", h.analog.rate_hz, where, aobj + "/data");
    Append2D(wi.analog.get(), 0, h.analog.samples, channels, h.analog.data.data(), where, aobj + "/data");
    wi.analog_samples = h.analog.samples;
  }
  if (joints > 0) {
    const std::string oobj = obj + "/orientations";
    wi.joints = joints;
    wi.orientations = CreateOrientations(g, joints, where, oobj);
    h5::WriteAttr(wi.orientations.get(), "skeleton", SkeletonJson(h.skeleton), where, oobj);
    h5::WriteAttr(wi.orientations.get(), "convention",
                  std::string("w x y z: global orientation, rotates the joint's axes into the lab frame"), where, oobj);
    AppendOrientationFrames(wi.orientations.get(), 0, h.orientations.frames(), joints, h.orientations.data().data(),
                            where, oobj);
    wi.orientation_frames = h.orientations.frames();
  }
  WriteEvents(g, h.events, where, obj);
  WriteProvenance(g, h.provenance, csw_version, imported_utc, where, obj);
  return writer;
}

void CorpusTransaction::WriteTake(const Take& take, IfTakeExists if_exists) {
  if (take.frames() > 0 && take.markers.markers() != static_cast<int64_t>(take.marker_names.size())) {
    throw InvalidInput("take '" + take.name + "' has " + std::to_string(take.markers.markers()) + " markers but " +
                       std::to_string(take.marker_names.size()) + " marker names");
  }
  TakeWriter w = BeginTake(take, if_exists);
  w.AppendFrames(take.markers.data().data(), take.frames());
  w.Finish();
}

}  // namespace csw
