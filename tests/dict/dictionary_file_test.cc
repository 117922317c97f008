// io/dictionary: round trip, the documented layout read with the HDF5 C API
// alone (docs/dictionary-format.md), and refusals (not a dictionary, newer
// version, a corpus never replaced).
#include "io/dictionary/dictionary_file.h"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "core/error.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

dict::Dictionary SmallDictionary() {
  dict::Dictionary d;
  d.models_fingerprint = std::string(64, 'a');
  d.corpus = "c.h5";
  d.models_file = "m.h5";
  d.keys_file = "k.h5";
  d.key_tier = "keys";
  d.hand_parameter_names = {"hand_p1", "hand_p2", "hand_p3"};
  for (int i = 0; i < 3; ++i) {
    dict::DikeyUnit u;
    u.take = "s" + std::to_string(i);
    u.index = i;
    u.from = KeyCode{i, 1};
    u.to = KeyCode{5, 8 - i};
    u.start_s = 0.5 + i;
    u.end_s = 0.8 + i;
    u.first_frame = 60 + 120 * i;
    u.rate_hz = 120;
    u.phasing_s = i == 2 ? std::numeric_limits<double>::quiet_NaN() : -0.05 * i;
    u.from_placement_lag_s = i == 1 ? std::numeric_limits<double>::quiet_NaN() : 0.01 * (i + 1);
    u.to_placement_lag_s = -0.02 * i;
    if (i == 0) u.to_type = KeyType::kCV;
    if (i == 1) u.to_type = KeyType::kVowelAlone;  // unit 2: unknown
    const int n = 2 + i;
    u.hand_params.resize(n, 3);
    u.forearm_in_head.resize(n, 6);
    u.head_pose.resize(n, 6);
    for (int r = 0; r < n; ++r) {
      for (int k = 0; k < 3; ++k) u.hand_params(r, k) = 100 * i + 10 * r + k;
      for (int k = 0; k < 6; ++k) {
        u.forearm_in_head(r, k) = 1000 + 100 * i + 10 * r + k;
        u.head_pose(r, k) = -(100 * i + 10 * r + k);
      }
    }
    d.dikeys.push_back(u);
  }
  d.face_parameter_names = {"jaw", "lips"};
  for (int i = 0; i < 2; ++i) {
    dict::DiphoneUnit p;
    p.take = "s" + std::to_string(i);
    p.index = 3 + i;
    p.phone1 = i == 0 ? "_" : "ʃ";
    p.phone2 = "ɑ̃";
    p.phone1_start_s = 1.0 + i;
    p.phone1_end_s = 1.1 + i;
    p.phone2_start_s = 1.1 + i;
    p.phone2_end_s = 1.3 + i;
    p.start_s = 1.05 + i;
    p.end_s = 1.2 + i;
    p.first_frame = 126 + 120 * i;
    p.rate_hz = 120;
    p.audio_path = "s" + std::to_string(i) + ".wav";
    p.face_params.resize(3 + i, 2);
    for (int r = 0; r < 3 + i; ++r) p.face_params.row(r) << 0.5 * r + i, -0.25 * r;
    d.diphones.push_back(p);
  }
  return d;
}

TEST(DictionaryFile, RoundTrip) {
  testing::TempDir dir;
  const std::string path = (dir / "d.h5").string();
  dict::Dictionary d = SmallDictionary();
  d.corpus_rate_hz = 120;
  d.corpus_p99_jump_mm = 15.25;
  d.corpus_max_jump_mm = 44.5;
  SaveDictionaryFile(path, d);
  const dict::Dictionary r = LoadDictionaryFile(path);
  EXPECT_EQ(r.corpus_rate_hz, 120);
  EXPECT_EQ(r.corpus_p99_jump_mm, 15.25);
  EXPECT_EQ(r.corpus_max_jump_mm, 44.5);
  EXPECT_EQ(r.models_fingerprint, d.models_fingerprint);
  EXPECT_EQ(r.corpus, "c.h5");
  EXPECT_EQ(r.models_file, "m.h5");
  EXPECT_EQ(r.keys_file, "k.h5");
  EXPECT_EQ(r.key_tier, "keys");
  EXPECT_EQ(r.hand_parameter_names, d.hand_parameter_names);
  ASSERT_EQ(r.dikeys.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const dict::DikeyUnit &a = d.dikeys[i], &b = r.dikeys[i];
    EXPECT_EQ(b.take, a.take);
    EXPECT_EQ(b.index, a.index);
    EXPECT_EQ(b.from, a.from);
    EXPECT_EQ(b.to, a.to);
    EXPECT_EQ(b.start_s, a.start_s);
    EXPECT_EQ(b.end_s, a.end_s);
    EXPECT_EQ(b.first_frame, a.first_frame);
    EXPECT_EQ(b.rate_hz, a.rate_hz);
    if (std::isnan(a.phasing_s))
      EXPECT_TRUE(std::isnan(b.phasing_s));
    else
      EXPECT_EQ(b.phasing_s, a.phasing_s);
    if (std::isnan(a.from_placement_lag_s))
      EXPECT_TRUE(std::isnan(b.from_placement_lag_s));
    else
      EXPECT_EQ(b.from_placement_lag_s, a.from_placement_lag_s);
    EXPECT_EQ(b.to_placement_lag_s, a.to_placement_lag_s);
    EXPECT_EQ(b.to_type, a.to_type);
    EXPECT_EQ(b.hand_params, a.hand_params);
    EXPECT_EQ(b.forearm_in_head, a.forearm_in_head);
    EXPECT_EQ(b.head_pose, a.head_pose);
  }
  ASSERT_EQ(r.diphones.size(), 2u);
  EXPECT_EQ(r.face_parameter_names, d.face_parameter_names);
  for (size_t i = 0; i < 2; ++i) {
    const dict::DiphoneUnit &a = d.diphones[i], &b = r.diphones[i];
    EXPECT_EQ(b.take, a.take);
    EXPECT_EQ(b.index, a.index);
    EXPECT_EQ(b.phone1, a.phone1);  // UTF-8 kept
    EXPECT_EQ(b.phone2, a.phone2);
    EXPECT_EQ(b.phone1_start_s, a.phone1_start_s);
    EXPECT_EQ(b.phone1_end_s, a.phone1_end_s);
    EXPECT_EQ(b.phone2_start_s, a.phone2_start_s);
    EXPECT_EQ(b.phone2_end_s, a.phone2_end_s);
    EXPECT_EQ(b.start_s, a.start_s);
    EXPECT_EQ(b.end_s, a.end_s);
    EXPECT_EQ(b.first_frame, a.first_frame);
    EXPECT_EQ(b.rate_hz, a.rate_hz);
    EXPECT_EQ(b.audio_path, a.audio_path);
    EXPECT_EQ(b.face_params, a.face_params);
  }
  // Saved again over itself: a dictionary file may be replaced.
  EXPECT_NO_THROW(SaveDictionaryFile(path, r));
}

// HDF5 C API helpers, no csw code.
std::string StringAttr(hid_t obj, const char* name) {
  const hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
  if (a < 0) return "<missing>";
  const hid_t t = H5Aget_type(a);
  std::string out;
  if (H5Tis_variable_str(t) > 0) {
    char* s = nullptr;
    const hid_t mt = H5Tget_native_type(t, H5T_DIR_DEFAULT);
    H5Aread(a, mt, &s);
    out = s ? s : "";
    H5free_memory(s);
    H5Tclose(mt);
  } else {
    out.resize(H5Tget_size(t));
    H5Aread(a, t, out.data());
    out.resize(std::strlen(out.c_str()));
  }
  H5Tclose(t);
  H5Aclose(a);
  return out;
}

int64_t IntAttr(hid_t obj, const char* name) {
  int64_t v = -1;
  const hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
  if (a < 0) return -1;
  H5Aread(a, H5T_NATIVE_INT64, &v);
  H5Aclose(a);
  return v;
}

std::vector<hsize_t> DatasetShape(hid_t file, const char* path) {
  const hid_t ds = H5Dopen2(file, path, H5P_DEFAULT);
  if (ds < 0) return {};
  const hid_t sp = H5Dget_space(ds);
  std::vector<hsize_t> dims(static_cast<size_t>(H5Sget_simple_extent_ndims(sp)));
  H5Sget_simple_extent_dims(sp, dims.data(), nullptr);
  H5Sclose(sp);
  H5Dclose(ds);
  return dims;
}

template <typename T>
std::vector<T> ReadAll(hid_t file, const char* path, hid_t type, size_t n) {
  std::vector<T> v(n);
  const hid_t ds = H5Dopen2(file, path, H5P_DEFAULT);
  if (ds < 0) return {};
  H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  H5Dclose(ds);
  return v;
}

TEST(DictionaryFile, TheDocumentedLayoutReadWithTheHdf5CApiAlone) {
  testing::TempDir dir;
  const std::string path = (dir / "d.h5").string();
  SaveDictionaryFile(path, SmallDictionary());
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  EXPECT_EQ(StringAttr(f, "format"), "csw-dictionary");
  EXPECT_EQ(IntAttr(f, "format_version"), 1);
  EXPECT_EQ(StringAttr(f, "models_fingerprint"), std::string(64, 'a'));
  EXPECT_EQ(StringAttr(f, "key_tier"), "keys");
  const hid_t g = H5Gopen2(f, "/dikeys", H5P_DEFAULT);
  ASSERT_GE(g, 0);
  EXPECT_EQ(IntAttr(g, "count"), 3);
  H5Gclose(g);
  // Per unit (3): codes as numbers, times, rows of the per-frame arrays.
  for (const char* name :
       {"/dikeys/take", "/dikeys/from_code", "/dikeys/to_code", "/dikeys/key_index", "/dikeys/from_placement",
        "/dikeys/from_shape", "/dikeys/to_placement", "/dikeys/to_shape", "/dikeys/first_frame", "/dikeys/offset",
        "/dikeys/frames", "/dikeys/start_s", "/dikeys/end_s", "/dikeys/duration_s", "/dikeys/phasing_s",
        "/dikeys/rate_hz", "/dikeys/from_placement_lag_s", "/dikeys/to_placement_lag_s", "/dikeys/to_type"}) {
    EXPECT_EQ(DatasetShape(f, name), std::vector<hsize_t>{3}) << name;
  }
  // Frames 2 + 3 + 4 = 9 rows, concatenated in unit order.
  EXPECT_EQ(DatasetShape(f, "/dikeys/hand_params"), (std::vector<hsize_t>{9, 3}));
  EXPECT_EQ(DatasetShape(f, "/dikeys/forearm_in_head"), (std::vector<hsize_t>{9, 6}));
  EXPECT_EQ(DatasetShape(f, "/dikeys/head_pose"), (std::vector<hsize_t>{9, 6}));
  EXPECT_EQ(DatasetShape(f, "/dikeys/hand_parameter_names"), std::vector<hsize_t>{3});
  EXPECT_EQ(ReadAll<int64_t>(f, "/dikeys/offset", H5T_NATIVE_INT64, 3), (std::vector<int64_t>{0, 2, 5}));
  EXPECT_EQ(ReadAll<int64_t>(f, "/dikeys/frames", H5T_NATIVE_INT64, 3), (std::vector<int64_t>{2, 3, 4}));
  EXPECT_EQ(ReadAll<int64_t>(f, "/dikeys/to_shape", H5T_NATIVE_INT64, 3), (std::vector<int64_t>{8, 7, 6}));
  const std::vector<double> hand = ReadAll<double>(f, "/dikeys/hand_params", H5T_NATIVE_DOUBLE, 27);
  // Row 5 = unit 2's first frame: 200, 201, 202 (row-major).
  EXPECT_EQ(hand[15], 200.0);
  EXPECT_EQ(hand[17], 202.0);
  const std::vector<double> dur = ReadAll<double>(f, "/dikeys/duration_s", H5T_NATIVE_DOUBLE, 3);
  EXPECT_NEAR(dur[1], 0.3, 1e-12);
  // Coverage: 6 × 6 and 9 × 9 counts, one row per succession.
  EXPECT_EQ(DatasetShape(f, "/coverage/placement_counts"), (std::vector<hsize_t>{6, 6}));
  EXPECT_EQ(DatasetShape(f, "/coverage/shape_counts"), (std::vector<hsize_t>{9, 9}));
  EXPECT_EQ(DatasetShape(f, "/coverage/successions"), std::vector<hsize_t>{3});
  // Diphones: per unit [2], face parameters [3 + 4 = 7][2].
  EXPECT_EQ(IntAttr(H5Gopen2(f, "/diphones", H5P_DEFAULT), "count"), 2);
  for (const char* name :
       {"/diphones/take", "/diphones/phone1", "/diphones/phone2", "/diphones/audio_path", "/diphones/phone_index",
        "/diphones/first_frame", "/diphones/offset", "/diphones/frames", "/diphones/phone1_start_s",
        "/diphones/phone1_end_s", "/diphones/phone2_start_s", "/diphones/phone2_end_s", "/diphones/start_s",
        "/diphones/end_s", "/diphones/duration_s", "/diphones/rate_hz", "/diphones/face_parameter_names"}) {
    EXPECT_EQ(DatasetShape(f, name), std::vector<hsize_t>{2}) << name;
  }
  EXPECT_EQ(DatasetShape(f, "/diphones/face_params"), (std::vector<hsize_t>{7, 2}));
  EXPECT_EQ(ReadAll<int64_t>(f, "/diphones/offset", H5T_NATIVE_INT64, 2), (std::vector<int64_t>{0, 3}));
  EXPECT_EQ(DatasetShape(f, "/coverage/diphones"), std::vector<hsize_t>{2});
  const std::vector<int64_t> pc = ReadAll<int64_t>(f, "/coverage/placement_counts", H5T_NATIVE_INT64, 36);
  EXPECT_EQ(pc[0 * 6 + 5], 1);  // 0 → 5
  EXPECT_EQ(pc[2 * 6 + 5], 1);  // 2 → 5
  H5Fclose(f);
}

TEST(DictionaryFile, AFileWithoutKeyTypesReadsWithTypesUnknown) {
  // Dictionaries written before the key types have no /dikeys/to_type.
  testing::TempDir dir;
  const std::string path = (dir / "d.h5").string();
  SaveDictionaryFile(path, SmallDictionary());
  ASSERT_TRUE(LoadDictionaryFile(path).dikeys[1].to_type.has_value());
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  ASSERT_GE(H5Ldelete(f, "/dikeys/to_type", H5P_DEFAULT), 0);
  H5Fclose(f);
  const dict::Dictionary d = LoadDictionaryFile(path);
  ASSERT_EQ(d.dikeys.size(), 3u);
  for (const dict::DikeyUnit& u : d.dikeys) EXPECT_FALSE(u.to_type.has_value());
  EXPECT_NEAR(d.dikeys[1].phasing_s, -0.05, 1e-15);  // the rest as before
}

TEST(DictionaryFile, AnUnknownKeyTypeIsOneClearError) {
  testing::TempDir dir;
  const std::string path = (dir / "d.h5").string();
  SaveDictionaryFile(path, SmallDictionary());
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  ASSERT_GE(H5Ldelete(f, "/dikeys/to_type", H5P_DEFAULT), 0);
  const hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, H5T_VARIABLE);
  const hsize_t n = 3;
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t ds = H5Dcreate2(f, "/dikeys/to_type", t, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(ds, 0);
  const char* values[3] = {"CV", "VC", ""};
  ASSERT_GE(H5Dwrite(ds, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, values), 0);
  H5Dclose(ds);
  H5Sclose(space);
  H5Tclose(t);
  H5Fclose(f);
  try {
    LoadDictionaryFile(path);
    FAIL();
  } catch (const ParseError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("/dikeys/to_type: unit 1 has type 'VC' (expected CV, V, C, rest or empty)"), std::string::npos)
        << what;
  }
}

TEST(DictionaryFile, RefusesWhatIsNotADictionary) {
  testing::TempDir dir;
  const std::string text = (dir / "x.h5").string();
  std::ofstream(text) << "not hdf5";
  try {
    LoadDictionaryFile(text);
    FAIL();
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("not an HDF5 file, so not a csw dictionary file"), std::string::npos)
        << e.what();
  }
  // Never replaced by a save.
  EXPECT_THROW(SaveDictionaryFile(text, SmallDictionary()), IoError);
  std::ifstream in(text);
  std::string content;
  std::getline(in, content);
  EXPECT_EQ(content, "not hdf5");

  // An HDF5 file of another format; then a dictionary of a newer version.
  const std::string other = (dir / "o.h5").string();
  hid_t f = H5Fcreate(other.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  H5Fclose(f);
  EXPECT_THROW(SaveDictionaryFile(other, SmallDictionary()), IoError);
  try {
    LoadDictionaryFile(other);
    FAIL();
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("not a csw dictionary file (format ''"), std::string::npos) << e.what();
  }
  const std::string newer = (dir / "n.h5").string();
  SaveDictionaryFile(newer, SmallDictionary());
  f = H5Fopen(newer.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  const int64_t two = 2;
  const hid_t a = H5Aopen(f, "format_version", H5P_DEFAULT);
  H5Awrite(a, H5T_NATIVE_INT64, &two);
  H5Aclose(a);
  H5Fclose(f);
  try {
    LoadDictionaryFile(newer);
    FAIL();
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("dictionary format version 2 is not supported (this csw reads 1 to 1)"),
              std::string::npos)
        << e.what();
  }
}

TEST(DictionaryFile, InconsistentUnitsAreRefusedBeforeWriting) {
  testing::TempDir dir;
  const std::string path = (dir / "d.h5").string();
  dict::Dictionary d = SmallDictionary();
  d.dikeys[1].head_pose.conservativeResize(1, 6);
  EXPECT_THROW(SaveDictionaryFile(path, d), InvalidInput);
  d = SmallDictionary();
  d.hand_parameter_names.pop_back();
  EXPECT_THROW(SaveDictionaryFile(path, d), InvalidInput);
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace csw
