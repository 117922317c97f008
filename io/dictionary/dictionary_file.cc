#include "io/dictionary/dictionary_file.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <limits>
#include <optional>

#include "core/error.h"
#include "core/file_util.h"
#include "io/corpus/hdf5_util.h"

namespace csw {

namespace fs = std::filesystem;
using h5::Handle;
using h5::Where;

namespace {

void WriteArray(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims, hid_t file_type, hid_t mem_type,
                const void* data, const Where& where, const std::string& object) {
  Handle space = h5::Own(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose, where,
                         "cannot create", object);
  Handle ds = h5::Own(H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                      H5Dclose, where, "cannot create", object);
  hsize_t n = 1;
  for (hsize_t d : dims) n *= d;
  if (n == 0) return;
  h5::Check(H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), where, "cannot write", object);
}

void WriteInts(hid_t loc, const std::string& name, const std::vector<int64_t>& v, const Where& where,
               const std::string& object) {
  WriteArray(loc, name, {static_cast<hsize_t>(v.size())}, H5T_STD_I64LE, H5T_NATIVE_INT64, v.data(), where, object);
}

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

void WriteRows(hid_t loc, const std::string& name, const RowMajor& m, const Where& where, const std::string& object) {
  WriteArray(loc, name, {static_cast<hsize_t>(m.rows()), static_cast<hsize_t>(m.cols())}, H5T_IEEE_F64LE,
             H5T_NATIVE_DOUBLE, m.data(), where, object);
}

void WriteIntMatrix(hid_t loc, const std::string& name, const Eigen::MatrixXi& m, const Where& where,
                    const std::string& object) {
  Eigen::Matrix<int64_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rm = m.cast<int64_t>();
  WriteArray(loc, name, {static_cast<hsize_t>(m.rows()), static_cast<hsize_t>(m.cols())}, H5T_STD_I64LE,
             H5T_NATIVE_INT64, rm.data(), where, object);
}

// Refuses to replace an existing file that is not a dictionary file.
void RefuseToClobber(const std::string& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) return;
  if (!fs::is_regular_file(st)) throw IoError(path, "exists and is not a regular file; not replacing it");
  if (fs::file_size(path, ec) == 0 && !ec) return;
  const std::string refuse = "refusing to replace it: ";
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    h5::TakeErrorMessage();
    throw IoError(path, refuse + "it is not an HDF5 file, so not a csw dictionary file (remove it first)");
  }
  const hid_t id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (id < 0) {
    const std::string detail = h5::TakeErrorMessage();
    throw IoError(path, refuse + "it is an HDF5 file that cannot be opened (" + detail + "); remove it first");
  }
  Handle file(id, H5Fclose);
  std::optional<std::string> format;
  try {
    format = h5::ReadAttrString(file.get(), "format", Where{path}, "/");
  } catch (const Error&) {
    format.reset();
  }
  if (!format || *format != kDictionaryFormatName) {
    throw IoError(path,
                  refuse + "it is not a csw dictionary file (format '" + format.value_or("") + "'); remove it first");
  }
}

void Validate(const dict::Dictionary& d) {
  const Eigen::Index p = static_cast<Eigen::Index>(d.hand_parameter_names.size());
  for (size_t i = 0; i < d.dikeys.size(); ++i) {
    const dict::DikeyUnit& u = d.dikeys[i];
    const std::string what =
        "dikey " + std::to_string(i) + " (take '" + u.take + "', " + dict::SuccessionCode(u.from, u.to) + ")";
    if (u.hand_params.cols() != p) {
      throw InvalidInput(what + ": " + std::to_string(u.hand_params.cols()) +
                         " hand parameters, the dictionary names " + std::to_string(p));
    }
    if (u.forearm_in_head.rows() != u.frames() || u.head_pose.rows() != u.frames() || u.forearm_in_head.cols() != 6 ||
        u.head_pose.cols() != 6) {
      throw InvalidInput(what + ": per-frame series of different lengths (or poses without 6 columns)");
    }
  }
  const Eigen::Index q = static_cast<Eigen::Index>(d.face_parameter_names.size());
  for (size_t i = 0; i < d.diphones.size(); ++i) {
    const dict::DiphoneUnit& u = d.diphones[i];
    if (u.face_params.cols() != q) {
      throw InvalidInput("diphone " + std::to_string(i) + " (take '" + u.take + "', " + u.phone1 + "+" + u.phone2 +
                         "): " + std::to_string(u.face_params.cols()) + " face parameters, the dictionary names " +
                         std::to_string(q));
    }
  }
}

void WriteDiphones(hid_t f, const dict::Dictionary& d, const Where& where) {
  const size_t n = d.diphones.size();
  Handle g = h5::CreateGroup(f, "diphones", where, "/diphones");
  h5::WriteAttr(g.get(), "count", static_cast<int64_t>(n), where, "/diphones");
  std::vector<std::string> take(n), phone1(n), phone2(n), audio(n);
  std::vector<int64_t> index(n), first_frame(n), offset(n), frames(n);
  std::vector<double> p1s(n), p1e(n), p2s(n), p2e(n), start_s(n), end_s(n), duration_s(n), rate_hz(n);
  int64_t total = 0;
  for (size_t i = 0; i < n; ++i) {
    const dict::DiphoneUnit& u = d.diphones[i];
    take[i] = u.take;
    phone1[i] = u.phone1;
    phone2[i] = u.phone2;
    audio[i] = u.audio_path;
    index[i] = u.index;
    first_frame[i] = u.first_frame;
    offset[i] = total;
    frames[i] = u.frames();
    total += u.frames();
    p1s[i] = u.phone1_start_s;
    p1e[i] = u.phone1_end_s;
    p2s[i] = u.phone2_start_s;
    p2e[i] = u.phone2_end_s;
    start_s[i] = u.start_s;
    end_s[i] = u.end_s;
    duration_s[i] = u.duration_s();
    rate_hz[i] = u.rate_hz;
  }
  RowMajor face(total, static_cast<Eigen::Index>(d.face_parameter_names.size()));
  for (size_t i = 0; i < n; ++i) face.middleRows(offset[i], frames[i]) = d.diphones[i].face_params;
  const hid_t gi = g.get();
  auto obj = [](const char* name) { return std::string("/diphones/") + name; };
  h5::WriteStrings(gi, "take", take, where, obj("take"));
  h5::WriteStrings(gi, "phone1", phone1, where, obj("phone1"));
  h5::WriteStrings(gi, "phone2", phone2, where, obj("phone2"));
  h5::WriteStrings(gi, "audio_path", audio, where, obj("audio_path"));
  WriteInts(gi, "phone_index", index, where, obj("phone_index"));
  WriteInts(gi, "first_frame", first_frame, where, obj("first_frame"));
  WriteInts(gi, "offset", offset, where, obj("offset"));
  WriteInts(gi, "frames", frames, where, obj("frames"));
  h5::WriteDoubles(gi, "phone1_start_s", p1s, where, obj("phone1_start_s"));
  h5::WriteDoubles(gi, "phone1_end_s", p1e, where, obj("phone1_end_s"));
  h5::WriteDoubles(gi, "phone2_start_s", p2s, where, obj("phone2_start_s"));
  h5::WriteDoubles(gi, "phone2_end_s", p2e, where, obj("phone2_end_s"));
  h5::WriteDoubles(gi, "start_s", start_s, where, obj("start_s"));
  h5::WriteDoubles(gi, "end_s", end_s, where, obj("end_s"));
  h5::WriteDoubles(gi, "duration_s", duration_s, where, obj("duration_s"));
  h5::WriteDoubles(gi, "rate_hz", rate_hz, where, obj("rate_hz"));
  h5::WriteStrings(gi, "face_parameter_names", d.face_parameter_names, where, obj("face_parameter_names"));
  WriteRows(gi, "face_params", face, where, obj("face_params"));
}

}  // namespace

void SaveDictionaryFile(const std::string& path, const dict::Dictionary& d) {
  if (path.empty()) throw IoError(path, "no output file name");
  Validate(d);
  WriterLock writer(path, "dictionary file");
  auto lock = h5::Lock();
  RefuseToClobber(path);
  const Where where{path};
  const std::string temp = HiddenSibling(path, ".csw-tmp." + std::to_string(::getpid()));
  struct Remove {
    std::string path;
    bool keep = false;
    ~Remove() {
      if (!keep) ::unlink(path.c_str());
    }
  } remove{temp};
  {
    Handle file = h5::Own(H5Fcreate(temp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, where,
                          "cannot create the temporary file", temp);
    const hid_t f = file.get();
    h5::WriteAttr(f, "format", std::string(kDictionaryFormatName), where, "/");
    h5::WriteAttr(f, "format_version", int64_t{kDictionaryFormatVersion}, where, "/");
    h5::WriteAttr(f, "csw_version", std::string(CSW_VERSION), where, "/");
    h5::WriteAttr(f, "created_utc", UtcNow(), where, "/");
    h5::WriteAttr(f, "models_fingerprint", d.models_fingerprint, where, "/");
    h5::WriteAttr(f, "models_file", d.models_file, where, "/");
    h5::WriteAttr(f, "corpus", d.corpus, where, "/");
    h5::WriteAttr(f, "keys_file", d.keys_file, where, "/");
    h5::WriteAttr(f, "key_tier", d.key_tier, where, "/");
    h5::WriteAttr(f, "corpus_rate_hz", d.corpus_rate_hz, where, "/");
    h5::WriteAttr(f, "corpus_p99_jump_mm", d.corpus_p99_jump_mm, where, "/");
    h5::WriteAttr(f, "corpus_max_jump_mm", d.corpus_max_jump_mm, where, "/");

    const size_t n = d.dikeys.size();
    Handle g = h5::CreateGroup(f, "dikeys", where, "/dikeys");
    h5::WriteAttr(g.get(), "count", static_cast<int64_t>(n), where, "/dikeys");
    std::vector<std::string> take(n), from_code(n), to_code(n), to_type(n);
    std::vector<int64_t> key_index(n), from_placement(n), from_shape(n), to_placement(n), to_shape(n), first_frame(n),
        offset(n), frames(n);
    std::vector<double> start_s(n), end_s(n), duration_s(n), phasing_s(n), rate_hz(n), from_lag(n), to_lag(n);
    int64_t total = 0;
    for (size_t i = 0; i < n; ++i) {
      const dict::DikeyUnit& u = d.dikeys[i];
      take[i] = u.take;
      from_code[i] = u.from.Text();
      to_code[i] = u.to.Text();
      to_type[i] = u.to_type ? KeyTypeText(*u.to_type) : "";
      key_index[i] = u.index;
      from_placement[i] = u.from.placement;
      from_shape[i] = u.from.shape;
      to_placement[i] = u.to.placement;
      to_shape[i] = u.to.shape;
      first_frame[i] = u.first_frame;
      offset[i] = total;
      frames[i] = u.frames();
      total += u.frames();
      start_s[i] = u.start_s;
      end_s[i] = u.end_s;
      duration_s[i] = u.duration_s();
      phasing_s[i] = u.phasing_s;
      from_lag[i] = u.from_placement_lag_s;
      to_lag[i] = u.to_placement_lag_s;
      rate_hz[i] = u.rate_hz;
    }
    const Eigen::Index p = static_cast<Eigen::Index>(d.hand_parameter_names.size());
    RowMajor hand(total, p), forearm(total, 6), head(total, 6);
    for (size_t i = 0; i < n; ++i) {
      const dict::DikeyUnit& u = d.dikeys[i];
      hand.middleRows(offset[i], frames[i]) = u.hand_params;
      forearm.middleRows(offset[i], frames[i]) = u.forearm_in_head;
      head.middleRows(offset[i], frames[i]) = u.head_pose;
    }
    const hid_t gi = g.get();
    auto obj = [](const char* name) { return std::string("/dikeys/") + name; };
    h5::WriteStrings(gi, "take", take, where, obj("take"));
    h5::WriteStrings(gi, "from_code", from_code, where, obj("from_code"));
    h5::WriteStrings(gi, "to_code", to_code, where, obj("to_code"));
    h5::WriteStrings(gi, "to_type", to_type, where, obj("to_type"));
    WriteInts(gi, "key_index", key_index, where, obj("key_index"));
    WriteInts(gi, "from_placement", from_placement, where, obj("from_placement"));
    WriteInts(gi, "from_shape", from_shape, where, obj("from_shape"));
    WriteInts(gi, "to_placement", to_placement, where, obj("to_placement"));
    WriteInts(gi, "to_shape", to_shape, where, obj("to_shape"));
    WriteInts(gi, "first_frame", first_frame, where, obj("first_frame"));
    WriteInts(gi, "offset", offset, where, obj("offset"));
    WriteInts(gi, "frames", frames, where, obj("frames"));
    h5::WriteDoubles(gi, "start_s", start_s, where, obj("start_s"));
    h5::WriteDoubles(gi, "end_s", end_s, where, obj("end_s"));
    h5::WriteDoubles(gi, "duration_s", duration_s, where, obj("duration_s"));
    h5::WriteDoubles(gi, "phasing_s", phasing_s, where, obj("phasing_s"));
    h5::WriteDoubles(gi, "from_placement_lag_s", from_lag, where, obj("from_placement_lag_s"));
    h5::WriteDoubles(gi, "to_placement_lag_s", to_lag, where, obj("to_placement_lag_s"));
    h5::WriteDoubles(gi, "rate_hz", rate_hz, where, obj("rate_hz"));
    h5::WriteStrings(gi, "hand_parameter_names", d.hand_parameter_names, where, obj("hand_parameter_names"));
    WriteRows(gi, "hand_params", hand, where, obj("hand_params"));
    WriteRows(gi, "forearm_in_head", forearm, where, obj("forearm_in_head"));
    WriteRows(gi, "head_pose", head, where, obj("head_pose"));

    WriteDiphones(f, d, where);

    const dict::Coverage c = dict::CoverageOfUnits(d.dikeys);
    Handle cg = h5::CreateGroup(f, "coverage", where, "/coverage");
    WriteIntMatrix(cg.get(), "placement_counts", c.placement, where, "/coverage/placement_counts");
    WriteIntMatrix(cg.get(), "shape_counts", c.shape, where, "/coverage/shape_counts");
    std::vector<std::string> codes;
    std::vector<int64_t> counts;
    for (const auto& [code, count] : c.dikeys) {
      codes.push_back(code);
      counts.push_back(count);
    }
    h5::WriteStrings(cg.get(), "successions", codes, where, "/coverage/successions");
    WriteInts(cg.get(), "succession_counts", counts, where, "/coverage/succession_counts");
    codes.clear();
    counts.clear();
    for (const auto& [code, count] : dict::DiphoneCoverage(d.diphones)) {
      codes.push_back(code);
      counts.push_back(count);
    }
    h5::WriteStrings(cg.get(), "diphones", codes, where, "/coverage/diphones");
    WriteInts(cg.get(), "diphone_counts", counts, where, "/coverage/diphone_counts");
    h5::Check(H5Fflush(f, H5F_SCOPE_GLOBAL), where, "cannot flush", temp);
    if (!file.Reset()) throw IoError(path, "cannot close " + temp + ": " + h5::TakeErrorMessage());
  }
  ReplaceFileDurably(temp, path);
  remove.keep = true;
}

namespace {

[[noreturn]] void Fail(const std::string& path, const std::string& what) {
  throw ParseError({path, std::nullopt, std::nullopt}, what);
}

// A numeric dataset of the given rank; returns its values (row-major) and dims.
std::vector<double> ReadNumbers(hid_t g, const std::string& name, size_t rank, std::vector<hsize_t>* dims,
                                const std::string& path, const std::string& group = "/dikeys/") {
  const std::string object = group + name;
  if (!h5::LinkExists(g, name)) Fail(path, "missing " + object);
  const Where where{path};
  Handle ds = h5::OpenDataset(g, name, where, object);
  *dims = h5::Shape(ds.get(), where, object);
  if (dims->size() != rank)
    Fail(path, object + " has rank " + std::to_string(dims->size()) + ", expected " + std::to_string(rank));
  return h5::ReadDoubles(g, name, where, object);
}

std::vector<double> ReadVector(hid_t g, const std::string& name, size_t n, const std::string& path,
                               const std::string& group = "/dikeys/") {
  std::vector<hsize_t> dims;
  std::vector<double> v = ReadNumbers(g, name, 1, &dims, path, group);
  if (v.size() != n) {
    Fail(path, group + name + " has " + std::to_string(v.size()) + " values, expected " + std::to_string(n));
  }
  return v;
}

RowMajor ReadRows(hid_t g, const std::string& name, hsize_t rows, hsize_t cols, const std::string& path,
                  const std::string& group = "/dikeys/") {
  std::vector<hsize_t> dims;
  std::vector<double> v = ReadNumbers(g, name, 2, &dims, path, group);
  if (dims[0] != rows || dims[1] != cols) {
    Fail(path, group + name + " has shape (" + std::to_string(dims[0]) + ", " + std::to_string(dims[1]) +
                   "), expected (" + std::to_string(rows) + ", " + std::to_string(cols) + ")");
  }
  return Eigen::Map<const RowMajor>(v.data(), static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
}

KeyCode Code(double placement, double shape, size_t i, const std::string& path, const char* which) {
  const int p = static_cast<int>(placement), s = static_cast<int>(shape);
  if (p != placement || s != shape || p < 0 || p > kMaxPlacement || s < 0 || s > kMaxShape) {
    Fail(path, "/dikeys: unit " + std::to_string(i) + " has a bad " + which + " key (" + std::to_string(placement) +
                   ", " + std::to_string(shape) + ")");
  }
  return KeyCode{p, s};
}

std::vector<std::string> ReadStringList(hid_t g, const std::string& name, size_t n, const std::string& path,
                                        const std::string& group) {
  if (!h5::LinkExists(g, name)) Fail(path, "missing " + group + name);
  std::vector<std::string> v = h5::ReadStrings(g, name, Where{path}, group + name);
  if (n != static_cast<size_t>(-1) && v.size() != n) {
    Fail(path, group + name + " has " + std::to_string(v.size()) + " values, expected " + std::to_string(n));
  }
  return v;
}

void ReadDiphones(hid_t f, const std::string& path, dict::Dictionary* d) {
  if (!h5::LinkExists(f, "diphones")) return;  // a dictionary of dikeys only
  const Where where{path};
  const std::string grp = "/diphones/";
  Handle g = h5::OpenGroup(f, "diphones", where, "/diphones");
  const hid_t gi = g.get();
  const std::optional<int64_t> count = h5::ReadAttrInt(gi, "count", where, "/diphones");
  if (!count || *count < 0) Fail(path, "missing or negative attribute count of /diphones");
  const size_t n = static_cast<size_t>(*count);
  const auto take = ReadStringList(gi, "take", n, path, grp);
  const auto phone1 = ReadStringList(gi, "phone1", n, path, grp);
  const auto phone2 = ReadStringList(gi, "phone2", n, path, grp);
  const auto audio = ReadStringList(gi, "audio_path", n, path, grp);
  d->face_parameter_names = ReadStringList(gi, "face_parameter_names", static_cast<size_t>(-1), path, grp);
  const auto index = ReadVector(gi, "phone_index", n, path, grp);
  const auto first_frame = ReadVector(gi, "first_frame", n, path, grp);
  const auto offset = ReadVector(gi, "offset", n, path, grp), frames = ReadVector(gi, "frames", n, path, grp);
  const auto p1s = ReadVector(gi, "phone1_start_s", n, path, grp), p1e = ReadVector(gi, "phone1_end_s", n, path, grp);
  const auto p2s = ReadVector(gi, "phone2_start_s", n, path, grp), p2e = ReadVector(gi, "phone2_end_s", n, path, grp);
  const auto start_s = ReadVector(gi, "start_s", n, path, grp), end_s = ReadVector(gi, "end_s", n, path, grp);
  const auto rate_hz = ReadVector(gi, "rate_hz", n, path, grp);
  std::vector<hsize_t> dims;
  ReadNumbers(gi, "face_params", 2, &dims, path, grp);
  const hsize_t total = dims[0];
  const RowMajor face = ReadRows(gi, "face_params", total, d->face_parameter_names.size(), path, grp);
  d->diphones.resize(n);
  for (size_t i = 0; i < n; ++i) {
    if (!(offset[i] >= 0 && frames[i] >= 0 && offset[i] + frames[i] <= static_cast<double>(total))) {
      Fail(path, "/diphones: unit " + std::to_string(i) + " has rows out of range");
    }
    dict::DiphoneUnit& u = d->diphones[i];
    u.take = take[i];
    u.index = static_cast<int>(index[i]);
    u.phone1 = phone1[i];
    u.phone2 = phone2[i];
    u.audio_path = audio[i];
    u.phone1_start_s = p1s[i];
    u.phone1_end_s = p1e[i];
    u.phone2_start_s = p2s[i];
    u.phone2_end_s = p2e[i];
    u.start_s = start_s[i];
    u.end_s = end_s[i];
    u.first_frame = static_cast<int64_t>(first_frame[i]);
    u.rate_hz = rate_hz[i];
    u.face_params = face.middleRows(static_cast<Eigen::Index>(offset[i]), static_cast<Eigen::Index>(frames[i]));
  }
}

}  // namespace

dict::Dictionary LoadDictionaryFile(const std::string& path) {
  auto lock = h5::Lock();
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path, "no such file");
  if (H5Fis_hdf5(path.c_str()) <= 0) {
    h5::TakeErrorMessage();
    Fail(path, "not an HDF5 file, so not a csw dictionary file");
  }
  const Where where{path};
  Handle file = h5::Own(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, where, "cannot open", path);
  const hid_t f = file.get();
  std::optional<std::string> format;
  try {
    format = h5::ReadAttrString(f, "format", where, "/");
  } catch (const Error&) {
    format.reset();
  }
  if (!format || *format != kDictionaryFormatName) {
    Fail(path,
         "not a csw dictionary file (format '" + format.value_or("") + "', expected '" + kDictionaryFormatName + "')");
  }
  const std::optional<int64_t> version = h5::ReadAttrInt(f, "format_version", where, "/");
  if (!version) Fail(path, "missing attribute format_version of /");
  if (*version > kDictionaryFormatVersion || *version < 1) {
    Fail(path, "dictionary format version " + std::to_string(*version) + " is not supported (this csw reads 1 to " +
                   std::to_string(kDictionaryFormatVersion) + ")");
  }
  dict::Dictionary d;
  auto attr = [&](const char* name) { return h5::ReadAttrString(f, name, where, "/").value_or(""); };
  d.models_fingerprint = attr("models_fingerprint");
  if (d.models_fingerprint.empty()) Fail(path, "missing attribute models_fingerprint of /");
  d.models_file = attr("models_file");
  d.corpus = attr("corpus");
  d.keys_file = attr("keys_file");
  d.key_tier = attr("key_tier");
  auto number = [&](const char* name) {
    return h5::ReadAttrDouble(f, name, where, "/").value_or(std::numeric_limits<double>::quiet_NaN());
  };
  d.corpus_rate_hz = number("corpus_rate_hz");
  d.corpus_p99_jump_mm = number("corpus_p99_jump_mm");
  d.corpus_max_jump_mm = number("corpus_max_jump_mm");
  if (!h5::LinkExists(f, "dikeys")) Fail(path, "missing group /dikeys");
  Handle g = h5::OpenGroup(f, "dikeys", where, "/dikeys");
  const hid_t gi = g.get();
  const std::optional<int64_t> count = h5::ReadAttrInt(gi, "count", where, "/dikeys");
  if (!count || *count < 0) Fail(path, "missing or negative attribute count of /dikeys");
  const size_t n = static_cast<size_t>(*count);
  if (!h5::LinkExists(gi, "take") || !h5::LinkExists(gi, "hand_parameter_names")) {
    Fail(path, "missing /dikeys/take or /dikeys/hand_parameter_names");
  }
  const std::vector<std::string> take = h5::ReadStrings(gi, "take", where, "/dikeys/take");
  if (take.size() != n)
    Fail(path, "/dikeys/take has " + std::to_string(take.size()) + " values, expected " + std::to_string(n));
  d.hand_parameter_names = h5::ReadStrings(gi, "hand_parameter_names", where, "/dikeys/hand_parameter_names");
  const auto key_index = ReadVector(gi, "key_index", n, path);
  const auto fp = ReadVector(gi, "from_placement", n, path), fs_ = ReadVector(gi, "from_shape", n, path);
  const auto tp = ReadVector(gi, "to_placement", n, path), ts = ReadVector(gi, "to_shape", n, path);
  const auto first_frame = ReadVector(gi, "first_frame", n, path);
  const auto offset = ReadVector(gi, "offset", n, path), frames = ReadVector(gi, "frames", n, path);
  const auto start_s = ReadVector(gi, "start_s", n, path), end_s = ReadVector(gi, "end_s", n, path);
  const auto phasing_s = ReadVector(gi, "phasing_s", n, path), rate_hz = ReadVector(gi, "rate_hz", n, path);
  // Optional (files before the placement lags): NaN = unknown.
  std::vector<double> from_lag(n, std::numeric_limits<double>::quiet_NaN()), to_lag = from_lag;
  if (h5::LinkExists(gi, "from_placement_lag_s")) from_lag = ReadVector(gi, "from_placement_lag_s", n, path);
  if (h5::LinkExists(gi, "to_placement_lag_s")) to_lag = ReadVector(gi, "to_placement_lag_s", n, path);
  // Optional (files before the key types): "" = unknown.
  std::vector<std::string> to_type(n);
  if (h5::LinkExists(gi, "to_type")) {
    to_type = h5::ReadStrings(gi, "to_type", where, "/dikeys/to_type");
    if (to_type.size() != n) {
      Fail(path, "/dikeys/to_type has " + std::to_string(to_type.size()) + " values, expected " + std::to_string(n));
    }
  }
  std::vector<hsize_t> dims;
  ReadNumbers(gi, "hand_params", 2, &dims, path);
  const hsize_t total = dims[0];
  const hsize_t p = d.hand_parameter_names.size();
  const RowMajor hand = ReadRows(gi, "hand_params", total, p, path);
  const RowMajor forearm = ReadRows(gi, "forearm_in_head", total, 6, path);
  const RowMajor head = ReadRows(gi, "head_pose", total, 6, path);
  d.dikeys.resize(n);
  for (size_t i = 0; i < n; ++i) {
    dict::DikeyUnit& u = d.dikeys[i];
    if (!(offset[i] >= 0 && frames[i] >= 0 && offset[i] + frames[i] <= static_cast<double>(total))) {
      Fail(path, "/dikeys: unit " + std::to_string(i) + " has rows out of range (offset " +
                     std::to_string(static_cast<int64_t>(offset[i])) + ", frames " +
                     std::to_string(static_cast<int64_t>(frames[i])) + ", " + std::to_string(total) + " rows)");
    }
    u.take = take[i];
    u.index = static_cast<int>(key_index[i]);
    u.from = Code(fp[i], fs_[i], i, path, "from");
    u.to = Code(tp[i], ts[i], i, path, "to");
    u.start_s = start_s[i];
    u.end_s = end_s[i];
    u.first_frame = static_cast<int64_t>(first_frame[i]);
    u.rate_hz = rate_hz[i];
    u.phasing_s = phasing_s[i];
    if (!to_type[i].empty()) {
      KeyType t;
      if (!ParseKeyTypeText(to_type[i], &t)) {
        Fail(path, "/dikeys/to_type: unit " + std::to_string(i) + " has type '" + to_type[i] +
                       "' (expected CV, V, C, rest or empty)");
      }
      u.to_type = t;
    }
    u.from_placement_lag_s = from_lag[i];
    u.to_placement_lag_s = to_lag[i];
    const auto o = static_cast<Eigen::Index>(offset[i]), k = static_cast<Eigen::Index>(frames[i]);
    u.hand_params = hand.middleRows(o, k);
    u.forearm_in_head = forearm.middleRows(o, k);
    u.head_pose = head.middleRows(o, k);
  }
  ReadDiphones(f, path, &d);
  return d;
}

}  // namespace csw
