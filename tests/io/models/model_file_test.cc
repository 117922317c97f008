// Model files (io/models/model_file.h, docs/model-format.md): exact round trips
// of models built from known numbers, the on-disk orientation of the arrays,
// damaged and foreign files, UpdateModelFile, and failed saves that must leave
// an existing file untouched.
#include "io/models/model_file.h"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include "analysis/keys/key_model.h"
#include "core/error.h"
#include "core/file_util.h"
#include "io/corpus/corpus.h"
#include "tests/io/models/model_test_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

namespace fs = std::filesystem;
using testing::ExpectSameFile;
using testing::ExpectSameMatrix;
using testing::TempDir;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------
// Models built from known numbers

ModelInfo MakeInfo(const std::string& tag) {
  ModelInfo info;
  info.corpus = "/data/corpus " + tag + " — é.h5";
  info.training_takes = {"sent01", "sent02@0:120", "phrase «" + tag + "»"};
  info.config_json = R"({"model": ")" + tag + R"(", "min_distance_mm": 2.0, "steps": [1, 2, 3]})";
  info.created_utc = "2026-11-22T06:00:00Z";
  info.csw_version = "0.1.0";
  info.training_frames = 12345;
  info.selected_frames = 678;
  info.training_rms_mm = 0.4375;
  return info;
}

// Value (r, c) of a deterministic, non-trivial matrix (distinct entries, not
// all exactly representable in decimal).
double Val(int seed, Eigen::Index r, Eigen::Index c) {
  return std::sin(0.37 * static_cast<double>(seed) + 1.1 * static_cast<double>(r) + 0.71 * static_cast<double>(c)) *
             (10.0 + static_cast<double>(seed)) +
         static_cast<double>(r) / 3.0;
}

Eigen::MatrixXd Filled(int seed, Eigen::Index rows, Eigen::Index cols) {
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index c = 0; c < cols; ++c)
    for (Eigen::Index r = 0; r < rows; ++r) m(r, c) = Val(seed, r, c);
  return m;
}

Eigen::VectorXd FilledVector(int seed, Eigen::Index n) { return Filled(seed, n, 1).col(0); }

RigidModel MakeRigid(const std::string& name, const std::vector<std::string>& markers, int k, int seed) {
  RigidModel m;
  m.name = name;
  m.markers = markers;
  m.reference = Filled(seed, 3, static_cast<Eigen::Index>(markers.size()));
  m.motion.mean = FilledVector(seed + 1, 6);
  m.motion.components = Filled(seed + 2, 6, k);
  m.motion.variances = FilledVector(seed + 3, k).cwiseAbs();
  m.motion.explained_fraction = m.motion.variances / (m.motion.variances.sum() + 1.0);
  m.motion.total_variance = m.motion.variances.sum() + 1.0;
  m.info = MakeInfo(name);
  return m;
}

FaceModel MakeFace() {
  FaceModel m;
  m.layout.head = {"head_front", "head_left", "head_right", "head_top"};
  m.layout.face = {"jaw", "lip_up", "lip_low", "corner_l", "corner_r"};
  m.layout.throat = {"throat_hi", "throat_lo"};
  m.layout.throat_weights = {kNaN, 0.25};  // first fitted, second fixed
  m.head = MakeRigid("head", m.layout.head, 4, 10);
  const int s = m.layout.num_shape_markers();  // 7
  m.head_weights = Eigen::VectorXd::Ones(s);
  m.head_weights[5] = 0.6180339887498949;
  m.head_weights[6] = 0.25;
  m.rest_pose.rotation = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  m.rest_pose.translation = Eigen::Vector3d(12.5, -300.25, 1400.125);
  m.rotation_offsets = Eigen::MatrixXd::Zero(s, 3);
  m.rotation_offsets.row(5) << -3.125, 40.5, 71.0625;  // the fitted throat marker's
  m.shape.mean = FilledVector(20, 3 * s);
  m.shape.steps = {{"jaw", {0}, 1}, {"lips", {1, 2, 3, 4}, 2}, {"throat", {5, 6}, 1}, {"residual", {}, 2}};
  m.shape.loadings = Filled(21, 3 * s, 6);
  m.shape.parameter_names = {"jaw", "lips1", "lips2", "throat", "residual1", "residual2"};
  m.shape.variance_explained = {0.5, 0.2, 0.1, 0.05, 0.04, 0.01};
  m.shape.residual_variance = 0.1;
  m.info = MakeInfo("face");
  return m;
}

HandModel MakeHand() {
  HandModel m;
  m.layout.forearm = {"wrist_in", "wrist_out", "forearm"};
  m.layout.hand = {"hand_a", "hand_b", "hand_c", "index_1", "index_2", "index_3", "thumb_tip"};
  m.layout.segments = {{"palm", -1, {0, 1, 2}}, {"index_prox", 0, {3, 4}}, {"index_dist", 1, {4, 5}}};
  m.forearm = MakeRigid("forearm", m.layout.forearm, 3, 30);
  for (int i = 0; i < 3; ++i) {
    m.rest.push_back(Eigen::AngleAxisd(0.2 + 0.5 * i, Eigen::Vector3d(1, -i, 2).normalized()).toRotationMatrix());
  }
  for (const auto& s : m.layout.segments) {
    for (const char* a : {"flexion", "spread", "twist"}) m.angle_names.push_back(s.name + "." + a);
  }
  const int n = static_cast<int>(m.angle_names.size());  // 9
  const int k = 4;
  m.shape.angle_pca.mean = FilledVector(40, n) / 10.0;
  m.shape.angle_pca.components = Filled(41, n, k);
  m.shape.angle_pca.variances = FilledVector(42, k).cwiseAbs();
  m.shape.angle_pca.variance_explained = {0.6, 0.2, 0.1, 0.05};
  m.shape.regression.coefficients = Filled(43, 1 + 2 * n, 3 * m.layout.num_shape_markers());
  m.shape.regression.coefficients.row(9).setZero();  // a dropped (constant) feature
  m.shape.regression.num_angles = n;
  m.shape.regression.rank = 15;
  m.shape.regression.rms_residual = 0.0625;
  m.shape.regression.warnings = {"cos(index_prox.twist) is constant over the training frames; dropped",
                                 "features are rank-deficient (rank 15 of 17)"};
  m.param_scale = m.shape.angle_pca.variances.cwiseSqrt();
  const Eigen::MatrixXd l = Filled(44, 21, 5);
  m.fill.mean = FilledVector(45, 21);
  m.fill.covariance = l * l.transpose() + 0.25 * Eigen::MatrixXd::Identity(21, 21);
  m.fill.ridge_mm2 = 0.125;
  m.fill.frames = 1207;
  m.fill.iterations = 37;
  m.info = MakeInfo("hand");
  return m;
}

ModelFile MakeAll() {
  ModelFile f;
  f.head = MakeRigid("head", {"h1", "h2", "h3", "h4", "h5"}, 3, 1);
  f.forearm = MakeRigid("forearm", {"f1", "f2", "f3"}, 6, 2);
  f.face = MakeFace();
  f.hand = MakeHand();
  return f;
}

// ---------------------------------------------------------------------------
// Files

std::string ReadBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteBytes(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << bytes;
}

// Names of the entries of dir, sorted.
// The files of a folder, without the writer-lock files (".<name>.csw-lock",
// left in place by design, docs/model-format.md).
std::vector<std::string> DirEntries(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.size() < 9 || name.compare(name.size() - 9, 9, ".csw-lock") != 0) out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The message of the exception E thrown by f ("" and a failure otherwise).
template <typename E, typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected exception type: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no exception";
  return "";
}

#define EXPECT_CONTAINS(haystack, needle)                          \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) \
      << "'" << (haystack) << "' lacks '" << (needle) << "'"

// Raw HDF5 access to damage files the way other tools could.
class RawFile {
 public:
  explicit RawFile(const std::string& path) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    id_ = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    EXPECT_GE(id_, 0) << path;
  }
  ~RawFile() {
    if (id_ >= 0) H5Fclose(id_);
  }
  hid_t id() const { return id_; }

  // Replaces the dataset at `path` by a float64 one of the given shape.
  void ReplaceDoubles(const std::string& path, const std::vector<hsize_t>& dims, const std::vector<double>& values) {
    if (H5Lexists(id_, path.c_str(), H5P_DEFAULT) > 0) {
      ASSERT_GE(H5Ldelete(id_, path.c_str(), H5P_DEFAULT), 0);
    }
    hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
    hid_t ds = H5Dcreate2(id_, path.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(ds, 0) << path;
    if (!values.empty()) {
      ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
    }
    H5Dclose(ds);
    H5Sclose(space);
  }
  std::vector<double> ReadDoubles(const std::string& path, std::vector<hsize_t>* dims) {
    hid_t ds = H5Dopen2(id_, path.c_str(), H5P_DEFAULT);
    EXPECT_GE(ds, 0) << path;
    hid_t space = H5Dget_space(ds);
    int rank = H5Sget_simple_extent_ndims(space);
    dims->assign(static_cast<size_t>(rank), 0);
    H5Sget_simple_extent_dims(space, dims->data(), nullptr);
    std::vector<double> v(static_cast<size_t>(H5Sget_simple_extent_npoints(space)));
    H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Sclose(space);
    H5Dclose(ds);
    return v;
  }
  void Delete(const std::string& path) { ASSERT_GE(H5Ldelete(id_, path.c_str(), H5P_DEFAULT), 0) << path; }
  void SetIntAttr(const std::string& obj, const std::string& name, int64_t value) {
    if (H5Aexists_by_name(id_, obj.c_str(), name.c_str(), H5P_DEFAULT) > 0) {
      ASSERT_GE(H5Adelete_by_name(id_, obj.c_str(), name.c_str(), H5P_DEFAULT), 0);
    }
    hid_t space = H5Screate(H5S_SCALAR);
    hid_t a =
        H5Acreate_by_name(id_, obj.c_str(), name.c_str(), H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(a, 0);
    ASSERT_GE(H5Awrite(a, H5T_NATIVE_INT64, &value), 0);
    H5Aclose(a);
    H5Sclose(space);
  }
  std::string StringAttr(const std::string& obj, const std::string& name) {
    hid_t a = H5Aopen_by_name(id_, obj.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
    EXPECT_GE(a, 0) << obj << " " << name;
    // Read as stored (h5py writes variable-length UTF-8; csw may write fixed
    // length): a memory type of the same size class and character set.
    const hid_t ft = H5Aget_type(a);
    const hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_cset(t, H5Tget_cset(ft));
    std::string s;
    if (H5Tis_variable_str(ft) > 0) {
      H5Tset_size(t, H5T_VARIABLE);
      char* p = nullptr;
      EXPECT_GE(H5Aread(a, t, &p), 0) << obj << " " << name;
      s = p != nullptr ? p : "";
      H5free_memory(p);
    } else {
      const size_t n = H5Tget_size(ft);
      H5Tset_size(t, n);
      std::string buf(n, '\0');
      EXPECT_GE(H5Aread(a, t, buf.data()), 0) << obj << " " << name;
      s = buf.c_str();
    }
    H5Tclose(t);
    H5Tclose(ft);
    H5Aclose(a);
    return s;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
};

// ---------------------------------------------------------------------------
// Round trips

TEST(ModelFile, AllFourModelsRoundTripExactly) {
  TempDir dir;
  const std::string path = (dir / "models.h5").string();
  const ModelFile saved = MakeAll();
  SaveModelFile(path, saved);
  ModelFile loaded = LoadModelFile(path);
  ExpectSameFile(saved, loaded);
  // Only the file itself is left: the temporary sibling was renamed.
  EXPECT_EQ(DirEntries(dir.path()), std::vector<std::string>{"models.h5"});
}

TEST(ModelFile, EachModelAloneRoundTrips) {
  TempDir dir;
  const ModelFile all = MakeAll();
  for (int which = 0; which < 4; ++which) {
    ModelFile one;
    if (which == 0) one.head = all.head;
    if (which == 1) one.forearm = all.forearm;
    if (which == 2) one.face = all.face;
    if (which == 3) one.hand = all.hand;
    const std::string path = (dir / ("one" + std::to_string(which) + ".h5")).string();
    SaveModelFile(path, one);
    ExpectSameFile(one, LoadModelFile(path));
  }
  // And none at all: a valid, empty model file.
  const std::string empty = (dir / "empty.h5").string();
  SaveModelFile(empty, ModelFile{});
  ExpectSameFile(ModelFile{}, LoadModelFile(empty));
}

TEST(ModelFile, EmptyListsAndLargeTextRoundTrip) {
  TempDir dir;
  ModelFile f;
  f.face = MakeFace();
  f.face->layout.throat.clear();  // no throat markers, no weights
  f.face->layout.throat_weights.clear();
  const int s = f.face->layout.num_shape_markers();  // 5
  f.face->head_weights = Eigen::VectorXd::Ones(s);
  f.face->rotation_offsets.resize(0, 0);  // as in files written before the throat rotation offsets
  f.face->shape.mean = FilledVector(50, 3 * s);
  f.face->shape.steps = {{"all", {}, 2}};
  f.face->shape.loadings = Filled(51, 3 * s, 2);
  f.face->shape.parameter_names = {"all1", "all2"};
  f.face->shape.variance_explained = {0.75, 0.25};
  f.face->info.training_takes.clear();
  f.face->info.config_json = std::string(300000, 'x') + "ü";  // beyond the 64 KiB compact attribute limit
  f.hand = MakeHand();
  f.hand->shape.regression.warnings.clear();
  f.hand->rest.clear();                               // = identity for every segment
  f.head = MakeRigid("head", {"a", "b", "c"}, 0, 7);  // no motion component kept
  const std::string path = (dir / "m.h5").string();
  SaveModelFile(path, f);
  ExpectSameFile(f, LoadModelFile(path));
}

// The loaded models compute exactly what the saved ones do.
TEST(ModelFile, LoadedModelsPredictIdentically) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  const ModelFile saved = MakeAll();
  SaveModelFile(path, saved);
  const ModelFile loaded = LoadModelFile(path);

  const Eigen::VectorXd p = FilledVector(60, saved.face->num_parameters());
  const Eigen::VectorXd a = saved.face->shape.Predict(p);
  const Eigen::VectorXd b = loaded.face->shape.Predict(p);
  ASSERT_EQ(a.size(), 3 * saved.face->layout.num_shape_markers());
  ExpectSameMatrix(a, b, "face shape prediction");
  std::vector<bool> visible(static_cast<size_t>(a.size()), true);
  for (size_t i = 0; i < visible.size(); i += 4) visible[i] = false;
  ExpectSameMatrix(saved.face->shape.Estimate(a, visible), loaded.face->shape.Estimate(b, visible),
                   "face shape estimate");

  const Eigen::VectorXd q = FilledVector(61, saved.hand->num_parameters()) / 20.0;
  const Eigen::VectorXd ha = saved.hand->shape.Predict(q);
  ASSERT_EQ(ha.size(), 3 * saved.hand->layout.num_shape_markers());
  ExpectSameMatrix(ha, loaded.hand->shape.Predict(q), "hand shape prediction");

  const Eigen::MatrixXd scores = Filled(62, 5, saved.head->motion.count());
  ExpectSameMatrix(saved.head->motion.Reconstruct(scores), loaded.head->motion.Reconstruct(scores),
                   "head motion reconstruction");
}

// The orientation documented in docs/model-format.md, read with the C API as
// h5py would.
TEST(ModelFile, DatasetsHaveTheDocumentedShapes) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  const ModelFile f = MakeAll();
  SaveModelFile(path, f);
  RawFile raw(path);
  EXPECT_EQ(raw.StringAttr("/", "format"), "csw-models");
  EXPECT_EQ(raw.StringAttr("/", "csw_version"), CSW_VERSION);
  EXPECT_EQ(raw.StringAttr("/", "created_utc").size(), std::string("2026-11-22T06:00:00Z").size());
  EXPECT_EQ(raw.StringAttr("/face/shape/steps/001", "name"), "lips");
  EXPECT_EQ(raw.StringAttr("/hand", "config_json"), f.hand->info.config_json);

  std::vector<hsize_t> dims;
  // Points: one row per marker.
  std::vector<double> ref = raw.ReadDoubles("/head_motion/reference", &dims);
  ASSERT_EQ(dims, (std::vector<hsize_t>{5, 3}));
  EXPECT_EQ(ref[3 * 4 + 1], f.head->reference(1, 4));
  // Matrices: the C++ shape, row-major.
  std::vector<double> load = raw.ReadDoubles("/face/shape/loadings", &dims);
  ASSERT_EQ(dims, (std::vector<hsize_t>{21, 6}));  // 3 × 7 shape markers, 6 parameters
  EXPECT_EQ(load[6 * 20 + 5], f.face->shape.loadings(20, 5));
  EXPECT_EQ(load[6 * 2 + 1], f.face->shape.loadings(2, 1));
  std::vector<double> coef = raw.ReadDoubles("/hand/shape/regression/coefficients", &dims);
  ASSERT_EQ(dims, (std::vector<hsize_t>{19, 21}));  // 1 + 2 × 9 features, 3 × 7 coordinates
  EXPECT_EQ(coef[21 * 18 + 3], f.hand->shape.regression.coefficients(18, 3));
  std::vector<double> comp = raw.ReadDoubles("/forearm_motion/motion/components", &dims);
  ASSERT_EQ(dims, (std::vector<hsize_t>{6, 6}));
  EXPECT_EQ(comp[6 * 1 + 4], f.forearm->motion.components(1, 4));
  std::vector<double> rot = raw.ReadDoubles("/face/rest_pose/rotation", &dims);
  ASSERT_EQ(dims, (std::vector<hsize_t>{3, 3}));
  EXPECT_EQ(rot[3 * 0 + 2], f.face->rest_pose.rotation(0, 2));
  std::vector<double> rest = raw.ReadDoubles("/hand/rest", &dims);
  ASSERT_EQ(dims, (std::vector<hsize_t>{3, 3, 3}));  // segments, then each matrix row by row
  EXPECT_EQ(rest[9 * 2 + 3 * 0 + 1], f.hand->rest[2](0, 1));
  std::vector<double> seg = raw.ReadDoubles("/hand/layout/segments/002/markers", &dims);
  EXPECT_EQ(seg, (std::vector<double>{4, 5}));
}

// ---------------------------------------------------------------------------
// Damaged and foreign files

TEST(ModelFile, MissingFileIsAnIoError) {
  TempDir dir;
  const std::string path = (dir / "nope.h5").string();
  std::string msg = ErrorOf<IoError>([&] { LoadModelFile(path); });
  EXPECT_CONTAINS(msg, path);
}

TEST(ModelFile, NonHdf5FileIsAParseError) {
  TempDir dir;
  const std::string path = (dir / "notes.h5").string();
  WriteBytes(path, "These are not the models you are looking for.\n");
  std::string msg = ErrorOf<ParseError>([&] { LoadModelFile(path); });
  EXPECT_CONTAINS(msg, path);
  EXPECT_CONTAINS(msg, "not an HDF5 file");
}

TEST(ModelFile, TruncatedFileIsAParseError) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  SaveModelFile(path, MakeAll());
  const std::string bytes = ReadBytes(path);
  for (size_t keep : {bytes.size() / 2, bytes.size() - 100, size_t{600}}) {
    WriteBytes(path, bytes.substr(0, keep));
    std::string msg = ErrorOf<ParseError>([&] { LoadModelFile(path); });
    EXPECT_CONTAINS(msg, path);
  }
}

TEST(ModelFile, CorpusGivenAsModelFileIsAParseError) {
  TempDir dir;
  const std::string path = (dir / "corpus.h5").string();
  {
    CorpusTransaction tx(path);
    Take t;
    t.name = "take01";
    t.rate_hz = 100;
    t.marker_names = {"A", "B"};
    t.markers = MarkerArray(4, 2);
    tx.WriteTake(t);
    tx.Commit();
  }
  std::string msg = ErrorOf<ParseError>([&] { LoadModelFile(path); });
  EXPECT_CONTAINS(msg, path);
  EXPECT_CONTAINS(msg, "csw corpus");

  // Nor is a corpus ever replaced by a model file.
  const std::string before = ReadBytes(path);
  msg = ErrorOf<IoError>([&] { SaveModelFile(path, MakeAll()); });
  EXPECT_CONTAINS(msg, path);
  EXPECT_CONTAINS(msg, "corpus");
  msg = ErrorOf<ParseError>([&] { UpdateModelFile(path, MakeAll()); });
  EXPECT_CONTAINS(msg, "csw corpus");
  EXPECT_EQ(ReadBytes(path), before);
  EXPECT_NO_THROW(Corpus::Open(path));
}

TEST(ModelFile, NewerVersionIsAParseError) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  SaveModelFile(path, MakeAll());
  RawFile(path).SetIntAttr("/", "format_version", kModelFormatVersion + 1);
  std::string msg = ErrorOf<ParseError>([&] { LoadModelFile(path); });
  EXPECT_CONTAINS(msg, path);
  EXPECT_CONTAINS(msg, "format_version 2 is newer");
}

struct Damage {
  std::string dataset;  // replaced, or deleted when dims is empty
  std::vector<hsize_t> dims;
  std::vector<double> values;  // empty: zeros
  std::string expected;        // in the message, besides the file and dataset
};

TEST(ModelFile, MisShapedOrMissingDatasetIsAParseErrorNamingIt) {
  TempDir dir;
  const std::string good = (dir / "good.h5").string();
  SaveModelFile(good, MakeAll());
  const std::string good_bytes = ReadBytes(good);
  std::vector<double> nan_ref(15, 1.0);
  nan_ref[7] = kNaN;
  const std::vector<Damage> cases = {
      {"/face/shape/loadings", {20, 6}, {}, "has shape (20, 6), expected (21, 6)"},
      {"/face/shape/loadings", {21, 5}, {}, "has shape (21, 5), expected (21, 6)"},
      {"/face/shape/mean", {21, 1}, {}, "has rank 2, expected 1"},
      {"/hand/shape/regression/coefficients", {19 * 21}, {}, "has rank 1, expected 2"},
      {"/hand/shape/regression/coefficients", {17, 21}, {}, "expected (19, 21)"},
      {"/hand/param_scale", {}, {}, "missing dataset"},
      {"/hand/gaussian_fill/covariance", {20, 21}, {}, "has shape (20, 21), expected (21, 21)"},
      {"/hand/gaussian_fill/mean", {20}, {}, "has 20 elements, expected 21"},
      {"/hand/param_scale", {3}, {1, 1, 1}, "has 3 elements, expected 4"},
      {"/head_motion/reference", {5, 3}, nan_ref, "non-finite value"},
      {"/head_motion/reference", {5, 2}, {}, "expected (points, 3)"},
      {"/forearm_motion/motion/mean", {5}, {}, "has 5 elements, expected 6"},
      {"/face/head_weights", {7}, {1, 1, 1, 1, 1, 1.5, 0.25}, "outside [0, 1]"},
      {"/face/rest_pose/rotation", {3, 3}, {1, 0, 0, 0, 1, 0, 0, 0, 2}, "is not a rotation"},
      {"/hand/rest",
       {3, 3, 3},
       {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 0, 0, 1, 0, 0, 0, -1},
       "matrix [2] is not a rotation"},
      {"/hand/rest", {2, 3, 3}, {}, "has 2 elements, expected 3"},
      {"/hand/rest", {3, 9}, {}, "has rank 2, expected 3"},
      {"/face/shape/steps/001/markers", {2}, {1, 9}, "index 9 at position 1 is outside 0..6"},
      {"/hand/layout/segments/001/markers", {2}, {3, 2.5}, "is not an integer index"},
      {"/hand/shape/angle_pca/variances", {4}, {1, 2, std::numeric_limits<double>::infinity(), 4}, "non-finite value"},
  };
  for (const Damage& d : cases) {
    SCOPED_TRACE(d.dataset + ": " + d.expected);
    const std::string path = (dir / "bad.h5").string();
    WriteBytes(path, good_bytes);
    {
      RawFile raw(path);
      if (d.dims.empty()) {
        raw.Delete(d.dataset);
      } else {
        hsize_t n = 1;
        for (hsize_t x : d.dims) n *= x;
        std::vector<double> v = d.values.empty() ? std::vector<double>(n, 0.5) : d.values;
        raw.ReplaceDoubles(d.dataset, d.dims, v);
      }
    }
    std::string msg = ErrorOf<ParseError>([&] { LoadModelFile(path); });
    EXPECT_CONTAINS(msg, path);
    EXPECT_CONTAINS(msg, d.dataset);
    EXPECT_CONTAINS(msg, d.expected);
  }
}

// A key model (/keys, analysis/keys/key_model.h): 9 shapes on 7 distances,
// 6 placements on 3 coordinates, 10 samples per class.
ModelFile MakeKeys() {
  keys::KeyTrainingSet set;
  set.shape_samples.resize(90, keys::kNumDistances);
  set.placement_samples.resize(60, 3);
  for (int i = 0; i < 90; ++i) {
    for (int d = 0; d < keys::kNumDistances; ++d) set.shape_samples(i, d) = 10 * (i % 9) + d + std::sin(i + d);
    set.shape_labels.push_back(i % 9);
  }
  for (int i = 0; i < 60; ++i) {
    for (int d = 0; d < 3; ++d) set.placement_samples(i, d) = 30 * (i % 6) - 10 * d + std::cos(i * d);
    set.placement_labels.push_back(i % 6);
  }
  keys::HandLayout layout;
  layout.proximal = {"T1", "I1", "M1", "R1", "L1"};
  layout.distal = {"TT", "IT", "MT", "RT", "LT"};
  layout.palm = {"P1", "P2", "P3"};
  layout.head = {"H1", "H2", "H3"};
  Eigen::Matrix3Xd head(3, 3);
  head << 0, 100, 0, 0, 0, 100, 0, 0, 0;
  ModelFile f;
  f.keys = keys::TrainKeyModel(set, layout, head, {});
  return f;
}

TEST(ModelFile, DamagedKeyModelIsOneParseErrorNamingTheDataset) {
  TempDir dir;
  const std::string good = (dir / "keys.h5").string();
  SaveModelFile(good, MakeKeys());
  ASSERT_TRUE(LoadModelFile(good).keys.has_value());
  const std::string good_bytes = ReadBytes(good);
  std::vector<double> not_pd(9 * 7 * 7, 0.0);  // every covariance 0 but one negative diagonal entry
  not_pd[0] = -1;
  const std::vector<Damage> cases = {
      {"/keys/shape/means", {9, 6}, {}, "expected (classes, features)"},
      {"/keys/shape/means", {9 * 7}, {}, "has rank 1, expected 2"},
      {"/keys/shape/covariances", {9, 7, 7}, not_pd, "the covariance of class shape 0 is not positive definite"},
      {"/keys/placement/priors", {}, {}, "missing dataset"},
      {"/keys/placement/means", {6, 3}, std::vector<double>(18, kNaN), "non-finite value (nan) at index 0"},
      {"/keys/head_reference", {3, 2}, {}, "has shape (3, 2), expected (points, 3)"},
  };
  for (const Damage& d : cases) {
    SCOPED_TRACE(d.dataset + ": " + d.expected);
    const std::string path = (dir / "bad.h5").string();
    WriteBytes(path, good_bytes);
    {
      RawFile raw(path);
      if (d.dims.empty()) {
        raw.Delete(d.dataset);
      } else {
        hsize_t n = 1;
        for (hsize_t x : d.dims) n *= x;
        raw.ReplaceDoubles(d.dataset, d.dims, d.values.empty() ? std::vector<double>(n, 0.5) : d.values);
      }
    }
    std::string msg = ErrorOf<ParseError>([&] { LoadModelFile(path); });
    EXPECT_CONTAINS(msg, path);
    EXPECT_CONTAINS(msg, d.dataset);
    EXPECT_CONTAINS(msg, d.expected);
  }
}

TEST(ModelFile, MisnumberedStepsAndWrongTypesAreParseErrors) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  SaveModelFile(path, MakeAll());
  const std::string good_bytes = ReadBytes(path);
  {
    RawFile raw(path);
    ASSERT_GE(H5Lmove(raw.id(), "/face/shape/steps/002", raw.id(), "/face/shape/steps/007", H5P_DEFAULT, H5P_DEFAULT),
              0);
  }
  std::string msg = ErrorOf<ParseError>([&] { LoadModelFile(path); });
  EXPECT_CONTAINS(msg, "/face/shape/steps");
  EXPECT_CONTAINS(msg, "'007'");

  WriteBytes(path, good_bytes);
  {
    RawFile raw(path);
    raw.ReplaceDoubles("/hand/angle_names", {9}, std::vector<double>(9, 1.0));  // numbers instead of names
  }
  msg = ErrorOf<ParseError>([&] { LoadModelFile(path); });
  EXPECT_CONTAINS(msg, path);
  EXPECT_CONTAINS(msg, "/hand/angle_names");

  WriteBytes(path, good_bytes);
  {
    RawFile raw(path);
    raw.Delete("/forearm_motion/motion");
  }
  msg = ErrorOf<ParseError>([&] { LoadModelFile(path); });
  EXPECT_CONTAINS(msg, "/forearm_motion/motion: missing group");
}

// ---------------------------------------------------------------------------
// Saving

TEST(ModelFile, UpdateKeepsTheModelsNotInTheUpdate) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  const ModelFile all = MakeAll();
  // Update of a file that does not exist yet creates it.
  ModelFile first;
  first.head = all.head;
  first.face = all.face;
  UpdateModelFile(path, first);
  ExpectSameFile(first, LoadModelFile(path));

  ModelFile update;
  update.hand = all.hand;
  update.face = MakeFace();
  update.face->shape.loadings *= 2.0;
  update.face->info.corpus = "other.h5";
  UpdateModelFile(path, update);

  ModelFile expected;
  expected.head = all.head;     // kept
  expected.face = update.face;  // replaced
  expected.hand = all.hand;     // added
  ExpectSameFile(expected, LoadModelFile(path));
  EXPECT_EQ(DirEntries(dir.path()), std::vector<std::string>{"m.h5"});
}

// Two `csw fit -o same.h5` at once: the second update must fail with the
// lock message instead of silently dropping the first one's model.
TEST(ModelFile, ConcurrentUpdateOfTheSameFileIsRefusedWithTheLockMessage) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  const ModelFile all = MakeAll();
  ModelFile first;
  first.head = all.head;
  UpdateModelFile(path, first);
  const std::string before = ReadBytes(path);
  int ready[2];
  int done[2];
  ASSERT_EQ(pipe(ready), 0);
  ASSERT_EQ(pipe(done), 0);
  pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // Child: another csw process in the middle of its update (holding the lock).
    int code = 0;
    try {
      WriterLock lock(path, "model file");
      char c = 'r';
      if (write(ready[1], &c, 1) != 1) code = 2;
      if (read(done[0], &c, 1) != 1) code = 3;
    } catch (...) {
      code = 4;
    }
    _exit(code);
  }
  char c = 0;
  ASSERT_EQ(read(ready[0], &c, 1), 1);
  ModelFile second;
  second.hand = all.hand;
  const std::string msg = ErrorOf<IoError>([&] { UpdateModelFile(path, second); });
  EXPECT_CONTAINS(msg, path);
  EXPECT_CONTAINS(msg, "is writing this model file");
  EXPECT_CONTAINS(msg, ".m.h5.csw-lock is locked");
  const std::string msg_save = ErrorOf<IoError>([&] { SaveModelFile(path, second); });
  EXPECT_CONTAINS(msg_save, "is writing this model file");
  EXPECT_EQ(ReadBytes(path), before);  // the holder's file is untouched
  ASSERT_EQ(write(done[1], "x", 1), 1);
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  for (int fd : {ready[0], ready[1], done[0], done[1]}) close(fd);
  // Once the lock is released the update goes through and keeps both models.
  UpdateModelFile(path, second);
  ModelFile expected;
  expected.head = all.head;
  expected.hand = all.hand;
  ExpectSameFile(expected, LoadModelFile(path));
}

// kill -9 of a process saving the same model file over and over: the file
// always loads as one of the two saved states, and the next save removes the
// killed writer's temporary file.
TEST(ModelFile, SigkillDuringRepeatedSavesLeavesOneCompleteFile) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  const ModelFile all = MakeAll();
  ModelFile a;
  a.head = all.head;
  ModelFile b = all;
  SaveModelFile(path, a);
  pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    try {
      for (int i = 0;; ++i) SaveModelFile(path, i % 2 == 0 ? b : a);
    } catch (...) {
    }
    _exit(3);
  }
  // Kill it after it has replaced the file several times (new inode per save).
  int saves_seen = 0;
  ino_t last = 0;
  for (int i = 0; i < 4000 && saves_seen < 6; ++i) {
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && st.st_ino != last) {
      last = st.st_ino;
      ++saves_seen;
    }
    usleep(1000 + (i % 7) * 300);
  }
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  ASSERT_GE(saves_seen, 3) << "the child did not save";
  const ModelFile back = LoadModelFile(path);
  if (back.hand) {
    ExpectSameFile(b, back);
  } else {
    ExpectSameFile(a, back);
  }
  SaveModelFile(path, a);
  EXPECT_EQ(DirEntries(dir.path()), std::vector<std::string>{"m.h5"});
  ExpectSameFile(a, LoadModelFile(path));
}

TEST(ModelFile, InconsistentModelIsRejectedBeforeWriting) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  SaveModelFile(path, MakeAll());
  const std::string before = ReadBytes(path);

  ModelFile bad = MakeAll();
  bad.face->shape.loadings.conservativeResize(20, Eigen::NoChange);
  std::string msg = ErrorOf<InvalidInput>([&] { SaveModelFile(path, bad); });
  EXPECT_CONTAINS(msg, path);
  EXPECT_CONTAINS(msg, "/face/shape/loadings");

  bad = MakeAll();
  bad.hand->layout.segments[1].parent = 2;  // parent after child
  msg = ErrorOf<InvalidInput>([&] { SaveModelFile(path, bad); });
  EXPECT_CONTAINS(msg, "/hand/layout/segments/001");

  bad = MakeAll();
  bad.forearm->markers[2] = bad.forearm->markers[0];
  msg = ErrorOf<InvalidInput>([&] { SaveModelFile(path, bad); });
  EXPECT_CONTAINS(msg, "appears twice");

  bad = MakeAll();
  bad.face->head_weights[6] = kNaN;  // NaN is only allowed in layout.throat_weights (= fitted)
  msg = ErrorOf<InvalidInput>([&] { UpdateModelFile(path, bad); });
  EXPECT_CONTAINS(msg, "/face/head_weights");

  EXPECT_EQ(ReadBytes(path), before);
  EXPECT_EQ(DirEntries(dir.path()), std::vector<std::string>{"m.h5"});
}

TEST(ModelFile, FailedSaveLeavesTheExistingFileByteIdentical) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  ModelFile original;
  original.head = MakeAll().head;
  SaveModelFile(path, original);
  const std::string before = ReadBytes(path);

  // The temporary sibling cannot be created (a directory sits there).
  const std::string temp = ModelFileTempPath(path);
  EXPECT_EQ(fs::path(temp).parent_path(), dir.path());
  fs::create_directory(temp);
  std::string msg = ErrorOf<IoError>([&] { SaveModelFile(path, MakeAll()); });
  EXPECT_CONTAINS(msg, path);
  EXPECT_EQ(ReadBytes(path), before);
  EXPECT_TRUE(fs::is_directory(temp));
  fs::remove(temp);

  // A directory that cannot be written (not testable as root, who may write anyway).
  ASSERT_EQ(::chmod(dir.path().c_str(), 0555), 0);
  if (::access(dir.path().c_str(), W_OK) != 0) {
    msg = ErrorOf<IoError>([&] { UpdateModelFile(path, MakeAll()); });
    EXPECT_CONTAINS(msg, path);
    EXPECT_EQ(ReadBytes(path), before);
  }
  ASSERT_EQ(::chmod(dir.path().c_str(), 0755), 0);
  ExpectSameFile(original, LoadModelFile(path));
  EXPECT_EQ(DirEntries(dir.path()), std::vector<std::string>{"m.h5"});

  // A path in a missing directory.
  const std::string missing = (dir / "no" / "such" / "m.h5").string();
  msg = ErrorOf<IoError>([&] { SaveModelFile(missing, MakeAll()); });
  EXPECT_CONTAINS(msg, missing);
  EXPECT_FALSE(fs::exists(dir / "no"));

  // A file that is not a model file is not replaced.
  const std::string notes = (dir / "notes.txt").string();
  WriteBytes(notes, "keep me\n");
  msg = ErrorOf<IoError>([&] { SaveModelFile(notes, MakeAll()); });
  EXPECT_CONTAINS(msg, "refusing to replace");
  EXPECT_EQ(ReadBytes(notes), "keep me\n");
}

TEST(ModelFile, SaveReplacesAnExistingModelFile) {
  TempDir dir;
  const std::string path = (dir / "m.h5").string();
  SaveModelFile(path, MakeAll());
  ModelFile only;
  only.forearm = MakeAll().forearm;
  SaveModelFile(path, only);  // replaces: the other models are gone
  ExpectSameFile(only, LoadModelFile(path));
  // An empty file (e.g. from mktemp) may be replaced and counts as no file for Update.
  const std::string empty = (dir / "empty.h5").string();
  WriteBytes(empty, "");
  UpdateModelFile(empty, only);
  ExpectSameFile(only, LoadModelFile(empty));
}

}  // namespace
}  // namespace csw
