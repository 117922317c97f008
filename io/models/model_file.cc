#include "io/models/model_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>
#include <set>
#include <system_error>

#include "core/error.h"
#include "core/file_util.h"
#include "io/corpus/hdf5_util.h"

#ifndef CSW_VERSION
#define CSW_VERSION "unknown"
#endif

namespace csw {
namespace {

namespace fs = std::filesystem;
using h5::Handle;
using h5::Where;

constexpr char kFormatName[] = "csw-models";
constexpr char kCorpusFormatName[] = "csw-corpus";
constexpr char kHeadGroup[] = "head_motion";
constexpr char kForearmGroup[] = "forearm_motion";
constexpr char kFaceGroup[] = "face";
constexpr char kHandGroup[] = "hand";
constexpr char kKeysGroup[] = "keys";
// Largest dataset (elements) the reader agrees to allocate; models are small.
constexpr hssize_t kMaxElements = hssize_t{1} << 28;
// Tolerance of the rest pose's orthonormality check.
constexpr double kRotationTolerance = 1e-6;

std::string Errno() { return std::strerror(errno); }

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string Str(int64_t v) { return std::to_string(v); }

// Name of the i-th member of an ordered list group (steps, segments): 000, 001, ...
std::string IndexName(size_t i) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%03zu", i);
  return buf;
}

// Reports a problem with one object of a model file: a ParseError naming the
// file when loading (the file is damaged or not ours), InvalidInput when saving
// (the model in memory is inconsistent and would not load back). Objects are
// named by their path in the file in both cases ("/face/shape/loadings").
class Checker {
 public:
  Checker(std::string file, bool loading) : where_{std::move(file)}, loading_(loading) {}
  [[noreturn]] void Fail(const std::string& object, const std::string& what) const {
    std::string msg = object.empty() ? what : object + ": " + what;
    if (loading_) throw ParseError({where_.file, std::nullopt, std::nullopt}, msg);
    throw InvalidInput((where_.file.empty() ? std::string("<output>") : where_.file) + ": cannot save: " + msg);
  }
  void Require(bool cond, const std::string& object, const std::string& what) const {
    if (!cond) Fail(object, what);
  }
  const Where& where() const { return where_; }

 private:
  Where where_;
  bool loading_;
};

// ---------------------------------------------------------------------------
// Validation (shared by load and save)

template <typename Derived>
void RequireFinite(const Eigen::DenseBase<Derived>& m, const std::string& object, const Checker& c) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    for (Eigen::Index i = 0; i < m.rows(); ++i) {
      if (!std::isfinite(m(i, j))) {
        std::string at = m.cols() == 1 ? "index " + Str(i) : "[" + Str(i) + ", " + Str(j) + "]";
        c.Fail(object, "non-finite value (" + Num(m(i, j)) + ") at " + at);
      }
    }
  }
}

void RequireFinite(const std::vector<double>& v, const std::string& object, const Checker& c) {
  RequireFinite(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())), object, c);
}

void RequireLength(int64_t actual, int64_t expected, const std::string& object, const std::string& why,
                   const Checker& c) {
  if (actual != expected) {
    c.Fail(object, "has " + Str(actual) + " elements, expected " + Str(expected) + " (" + why + ")");
  }
}

void RequireShape(const Eigen::MatrixXd& m, int64_t rows, int64_t cols, const std::string& object,
                  const std::string& why, const Checker& c) {
  if (m.rows() != rows || m.cols() != cols) {
    c.Fail(object, "has shape (" + Str(m.rows()) + ", " + Str(m.cols()) + "), expected (" + Str(rows) + ", " +
                       Str(cols) + ") (" + why + ")");
  }
}

// Marker names: non-empty and unique within `seen` (which spans a model's
// cluster and shape markers).
void RequireNames(const std::vector<std::string>& names, size_t min_count, const std::string& object,
                  std::set<std::string>& seen, const Checker& c) {
  if (names.size() < min_count) {
    c.Fail(object, "has " + Str(static_cast<int64_t>(names.size())) + " markers, at least " +
                       Str(static_cast<int64_t>(min_count)) + " are needed");
  }
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i].empty()) c.Fail(object, "marker " + Str(static_cast<int64_t>(i)) + " has an empty name");
    if (!seen.insert(names[i]).second) c.Fail(object, "marker name '" + names[i] + "' appears twice in the model");
  }
}

void RequireIndices(const std::vector<int>& indices, int count, const std::string& object, const std::string& what,
                    const Checker& c) {
  std::set<int> seen;
  for (size_t i = 0; i < indices.size(); ++i) {
    int v = indices[i];
    if (v < 0 || v >= count) {
      c.Fail(object, "index " + Str(v) + " at position " + Str(static_cast<int64_t>(i)) + " is outside 0.." +
                         Str(count - 1) + " (" + what + ")");
    }
    if (!seen.insert(v).second) c.Fail(object, "index " + Str(v) + " appears twice");
  }
}

void ValidateInfo(const ModelInfo& info, const std::string& object, const Checker& c) {
  c.Require(info.training_frames >= 0, object, "attribute training_frames is negative");
  c.Require(info.selected_frames >= 0, object, "attribute selected_frames is negative");
  c.Require(std::isfinite(info.training_rms_mm) && info.training_rms_mm >= 0, object,
            "attribute training_rms_mm is not a finite non-negative number (" + Num(info.training_rms_mm) + ")");
}

void ValidatePca(const Pca& p, const std::string& object, const Checker& c) {
  RequireLength(p.mean.size(), 6, object + "/mean", "the 6 pose parameters rx ry rz tx ty tz", c);
  RequireFinite(p.mean, object + "/mean", c);
  int64_t k = p.components.cols();
  c.Require(k <= 6, object + "/components", "has " + Str(k) + " components, at most 6 are possible");
  RequireShape(p.components, 6, k, object + "/components", "6 pose parameters × components", c);
  RequireFinite(p.components, object + "/components", c);
  RequireLength(p.variances.size(), k, object + "/variances", "one per component", c);
  RequireFinite(p.variances, object + "/variances", c);
  RequireLength(p.explained_fraction.size(), k, object + "/explained_fraction", "one per component", c);
  RequireFinite(p.explained_fraction, object + "/explained_fraction", c);
  c.Require(std::isfinite(p.total_variance) && p.total_variance >= 0, object,
            "attribute total_variance is not a finite non-negative number (" + Num(p.total_variance) + ")");
}

void ValidateRigid(const RigidModel& m, const std::string& object, const Checker& c) {
  std::set<std::string> seen;
  RequireNames(m.markers, 3, object + "/markers", seen, c);
  const int64_t n = static_cast<int64_t>(m.markers.size());
  if (m.reference.cols() != n) {
    c.Fail(object + "/reference", "holds " + Str(m.reference.cols()) + " points, expected " + Str(n) +
                                      " (one per marker of " + object + "/markers)");
  }
  RequireFinite(m.reference.transpose(), object + "/reference", c);
  ValidatePca(m.motion, object + "/motion", c);
  ValidateInfo(m.info, object, c);
}

// `which` names the matrix within a stack of them (" [2]"), or is empty.
void ValidateRotation(const Eigen::Matrix3d& r, const std::string& object, const Checker& c,
                      const std::string& which = "") {
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(r(i, j))) {
        c.Fail(object, "non-finite value (" + Num(r(i, j)) + ") at" + which + " [" + Str(i) + ", " + Str(j) + "]");
      }
    }
  }
  double err = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  c.Require(err <= kRotationTolerance && r.determinant() > 0, object,
            "matrix" + which + " is not a rotation (|RᵀR − I| = " + Num(err) + ", det = " + Num(r.determinant()) + ")");
}

void ValidateGuidedPca(const GuidedPcaModel& s, int shape_markers, const std::string& object, const Checker& c) {
  const int64_t coords = 3 * int64_t{shape_markers};
  const std::string why = "3 × " + Str(shape_markers) + " shape markers";
  RequireLength(s.mean.size(), coords, object + "/mean", why, c);
  RequireFinite(s.mean, object + "/mean", c);
  // The steps fix the number of parameters.
  int64_t p = 0;
  for (size_t i = 0; i < s.steps.size(); ++i) {
    const GuidedPcaStep& step = s.steps[i];
    const std::string so = object + "/steps/" + IndexName(i);
    c.Require(step.components >= 1, so, "attribute components is " + Str(step.components) + ", at least 1 is needed");
    RequireIndices(step.markers, shape_markers, so + "/markers", "shape marker indices", c);
    p += step.components;
  }
  RequireShape(s.loadings, coords, p, object + "/loadings", why + " × " + Str(p) + " parameters of the steps", c);
  RequireFinite(s.loadings, object + "/loadings", c);
  RequireLength(static_cast<int64_t>(s.parameter_names.size()), p, object + "/parameter_names", "one per parameter", c);
  RequireLength(static_cast<int64_t>(s.variance_explained.size()), p, object + "/variance_explained",
                "one per parameter", c);
  RequireFinite(s.variance_explained, object + "/variance_explained", c);
  c.Require(std::isfinite(s.residual_variance), object,
            "attribute residual_variance is not finite (" + Num(s.residual_variance) + ")");
}

void ValidateFace(const FaceModel& m, const std::string& object, const Checker& c) {
  const FaceLayout& l = m.layout;
  std::set<std::string> seen;
  RequireNames(l.head, 3, object + "/layout/head", seen, c);
  RequireNames(l.face, 0, object + "/layout/face", seen, c);
  RequireNames(l.throat, 0, object + "/layout/throat", seen, c);
  const int shapes = l.num_shape_markers();
  c.Require(shapes >= 1, object + "/layout", "has no face or throat marker");
  if (!l.throat_weights.empty()) {
    RequireLength(static_cast<int64_t>(l.throat_weights.size()), static_cast<int64_t>(l.throat.size()),
                  object + "/layout/throat_weights", "empty or one per throat marker", c);
  }
  for (size_t i = 0; i < l.throat_weights.size(); ++i) {
    double w = l.throat_weights[i];
    c.Require(
        std::isnan(w) || (w >= 0 && w <= 1), object + "/layout/throat_weights",
        "value " + Num(w) + " at index " + Str(static_cast<int64_t>(i)) + " is neither NaN (fitted) nor in [0, 1]");
  }
  ValidateRigid(m.head, object + "/head", c);
  c.Require(m.head.markers == l.head, object + "/head/markers", "differs from " + object + "/layout/head");
  RequireLength(m.head_weights.size(), shapes, object + "/head_weights", "one per shape marker", c);
  RequireFinite(m.head_weights, object + "/head_weights", c);
  for (Eigen::Index i = 0; i < m.head_weights.size(); ++i) {
    double w = m.head_weights[i];
    c.Require(w >= 0 && w <= 1, object + "/head_weights",
              "value " + Num(w) + " at index " + Str(i) + " is outside [0, 1]");
  }
  ValidateRotation(m.rest_pose.rotation, object + "/rest_pose/rotation", c);
  RequireFinite(m.rest_pose.translation, object + "/rest_pose/translation", c);
  if (m.rotation_offsets.size() > 0) {
    RequireShape(m.rotation_offsets, shapes, 3, object + "/rotation_offsets", "one row (x y z, mm) per shape marker",
                 c);
    RequireFinite(m.rotation_offsets, object + "/rotation_offsets", c);
  }
  ValidateGuidedPca(m.shape, shapes, object + "/shape", c);
  ValidateInfo(m.info, object, c);
}

void ValidateHand(const HandModel& m, const std::string& object, const Checker& c) {
  const HandLayout& l = m.layout;
  std::set<std::string> seen;
  RequireNames(l.forearm, 3, object + "/layout/forearm", seen, c);
  RequireNames(l.hand, 1, object + "/layout/hand", seen, c);
  const int hands = l.num_shape_markers();
  for (size_t i = 0; i < l.segments.size(); ++i) {
    const HandSegmentDef& s = l.segments[i];
    const std::string so = object + "/layout/segments/" + IndexName(i);
    c.Require(!s.name.empty(), so, "attribute name is empty");
    c.Require(s.parent >= -1 && s.parent < static_cast<int>(i), so,
              "attribute parent is " + Str(s.parent) + "; it must be -1 (forearm) or an earlier segment");
    size_t min_markers = s.parent < 0 ? 3 : 2;
    c.Require(s.markers.size() >= min_markers, so + "/markers",
              "has " + Str(static_cast<int64_t>(s.markers.size())) + " markers, at least " +
                  Str(static_cast<int64_t>(min_markers)) + " are needed");
    RequireIndices(s.markers, hands, so + "/markers", "hand marker indices", c);
  }
  if (!m.rest.empty()) {
    RequireLength(static_cast<int64_t>(m.rest.size()), static_cast<int64_t>(l.segments.size()), object + "/rest",
                  "empty or one rotation per segment", c);
  }
  for (size_t i = 0; i < m.rest.size(); ++i) {
    ValidateRotation(m.rest[i], object + "/rest", c, " [" + Str(static_cast<int64_t>(i)) + "]");
  }
  ValidateRigid(m.forearm, object + "/forearm", c);
  c.Require(m.forearm.markers == l.forearm, object + "/forearm/markers", "differs from " + object + "/layout/forearm");

  const AnglePca& a = m.shape.angle_pca;
  const int64_t n = static_cast<int64_t>(m.angle_names.size());
  for (size_t i = 0; i < m.angle_names.size(); ++i) {
    c.Require(!m.angle_names[i].empty(), object + "/angle_names", "name " + Str(static_cast<int64_t>(i)) + " is empty");
  }
  const std::string ao = object + "/shape/angle_pca";
  RequireLength(a.mean.size(), n, ao + "/mean", "one per angle of " + object + "/angle_names", c);
  RequireFinite(a.mean, ao + "/mean", c);
  const int64_t k = a.components.cols();
  c.Require(k <= n, ao + "/components", "has " + Str(k) + " components for " + Str(n) + " angles");
  RequireShape(a.components, n, k, ao + "/components", "angles × parameters", c);
  RequireFinite(a.components, ao + "/components", c);
  RequireLength(a.variances.size(), k, ao + "/variances", "one per parameter", c);
  RequireFinite(a.variances, ao + "/variances", c);
  RequireLength(static_cast<int64_t>(a.variance_explained.size()), k, ao + "/variance_explained", "one per parameter",
                c);
  RequireFinite(a.variance_explained, ao + "/variance_explained", c);

  const HandRegression& r = m.shape.regression;
  const std::string ro = object + "/shape/regression";
  c.Require(r.num_angles == n, ro, "attribute num_angles is " + Str(r.num_angles) + ", expected " + Str(n));
  RequireShape(r.coefficients, 1 + 2 * n, 3 * int64_t{hands}, ro + "/coefficients",
               "1 + 2 × " + Str(n) + " angle features × 3 × " + Str(hands) + " hand marker coordinates", c);
  RequireFinite(r.coefficients, ro + "/coefficients", c);
  c.Require(r.rank >= 0 && r.rank <= 2 * n, ro, "attribute rank is " + Str(r.rank) + ", outside 0.." + Str(2 * n));
  c.Require(std::isfinite(r.rms_residual) && r.rms_residual >= 0, ro,
            "attribute rms_residual is not a finite non-negative number (" + Num(r.rms_residual) + ")");

  if (!m.fill.empty()) {
    const std::string fo = object + "/gaussian_fill";
    RequireLength(m.fill.mean.size(), 3 * int64_t{hands}, fo + "/mean", "3 per hand marker", c);
    RequireFinite(m.fill.mean, fo + "/mean", c);
    RequireShape(m.fill.covariance, 3 * int64_t{hands}, 3 * int64_t{hands}, fo + "/covariance",
                 "3 per hand marker, squared", c);
    RequireFinite(m.fill.covariance, fo + "/covariance", c);
    c.Require(m.fill.ridge_mm2 >= 0 && std::isfinite(m.fill.ridge_mm2), fo, "attribute ridge_mm2 must be >= 0");
    for (Eigen::Index i = 0; i < m.fill.covariance.rows(); ++i) {
      c.Require(m.fill.covariance(i, i) >= 0, fo + "/covariance",
                "diagonal value " + Num(m.fill.covariance(i, i)) + " at index " + Str(i) + " is negative");
    }
  }
  RequireLength(m.param_scale.size(), k, object + "/param_scale", "one per angle PCA parameter", c);
  RequireFinite(m.param_scale, object + "/param_scale", c);
  for (Eigen::Index i = 0; i < m.param_scale.size(); ++i) {
    c.Require(m.param_scale[i] > 0, object + "/param_scale",
              "value " + Num(m.param_scale[i]) + " at index " + Str(i) + " is not positive");
  }
  ValidateInfo(m.info, object, c);
}

// ---------------------------------------------------------------------------
// Writing

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

void WriteVector(hid_t loc, const std::string& name, const Eigen::VectorXd& v, const Where& where,
                 const std::string& object) {
  WriteArray(loc, name, {static_cast<hsize_t>(v.size())}, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.data(), where, object);
}

void WriteVector(hid_t loc, const std::string& name, const std::vector<double>& v, const Where& where,
                 const std::string& object) {
  WriteArray(loc, name, {static_cast<hsize_t>(v.size())}, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.data(), where, object);
}

// A matrix with the C++ shape: dataset (rows, cols), stored row by row.
void WriteMatrix(hid_t loc, const std::string& name, const Eigen::MatrixXd& m, const Where& where,
                 const std::string& object) {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rm = m;
  WriteArray(loc, name, {static_cast<hsize_t>(m.rows()), static_cast<hsize_t>(m.cols())}, H5T_IEEE_F64LE,
             H5T_NATIVE_DOUBLE, rm.data(), where, object);
}

// 3 × N points as dataset (N, 3): one row per point (the column-major 3 × N
// buffer is exactly the row-major N × 3 one).
void WritePoints(hid_t loc, const std::string& name, const Eigen::Matrix3Xd& p, const Where& where,
                 const std::string& object) {
  WriteArray(loc, name, {static_cast<hsize_t>(p.cols()), 3}, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.data(), where,
             object);
}

void WriteIndices(hid_t loc, const std::string& name, const std::vector<int>& v, const Where& where,
                  const std::string& object) {
  std::vector<int64_t> w(v.begin(), v.end());
  WriteArray(loc, name, {static_cast<hsize_t>(w.size())}, H5T_STD_I64LE, H5T_NATIVE_INT64, w.data(), where, object);
}

void WriteInfo(hid_t g, const ModelInfo& info, const Where& where, const std::string& object) {
  h5::WriteAttr(g, "corpus", info.corpus, where, object);
  h5::WriteAttr(g, "training_takes", info.training_takes, where, object);
  h5::WriteAttr(g, "config_json", info.config_json, where, object);
  h5::WriteAttr(g, "created_utc", info.created_utc, where, object);
  h5::WriteAttr(g, "csw_version", info.csw_version, where, object);
  h5::WriteAttr(g, "training_frames", int64_t{info.training_frames}, where, object);
  h5::WriteAttr(g, "selected_frames", int64_t{info.selected_frames}, where, object);
  h5::WriteAttr(g, "training_rms_mm", info.training_rms_mm, where, object);
}

void WriteRigid(hid_t parent, const std::string& name, const RigidModel& m, const Where& where,
                const std::string& object) {
  Handle g = h5::CreateGroup(parent, name, where, object);
  h5::WriteAttr(g.get(), "name", m.name, where, object);
  WriteInfo(g.get(), m.info, where, object);
  h5::WriteStrings(g.get(), "markers", m.markers, where, object + "/markers");
  WritePoints(g.get(), "reference", m.reference, where, object + "/reference");
  const std::string mo = object + "/motion";
  Handle mg = h5::CreateGroup(g.get(), "motion", where, mo);
  h5::WriteAttr(mg.get(), "total_variance", m.motion.total_variance, where, mo);
  WriteVector(mg.get(), "mean", m.motion.mean, where, mo + "/mean");
  WriteMatrix(mg.get(), "components", m.motion.components, where, mo + "/components");
  WriteVector(mg.get(), "variances", m.motion.variances, where, mo + "/variances");
  WriteVector(mg.get(), "explained_fraction", m.motion.explained_fraction, where, mo + "/explained_fraction");
}

void WriteFace(hid_t parent, const FaceModel& m, const Where& where) {
  const std::string object = std::string("/") + kFaceGroup;
  Handle g = h5::CreateGroup(parent, kFaceGroup, where, object);
  WriteInfo(g.get(), m.info, where, object);

  const std::string lo = object + "/layout";
  Handle lg = h5::CreateGroup(g.get(), "layout", where, lo);
  h5::WriteStrings(lg.get(), "head", m.layout.head, where, lo + "/head");
  h5::WriteStrings(lg.get(), "face", m.layout.face, where, lo + "/face");
  h5::WriteStrings(lg.get(), "throat", m.layout.throat, where, lo + "/throat");
  WriteVector(lg.get(), "throat_weights", m.layout.throat_weights, where, lo + "/throat_weights");

  WriteRigid(g.get(), "head", m.head, where, object + "/head");
  WriteVector(g.get(), "head_weights", m.head_weights, where, object + "/head_weights");
  if (m.rotation_offsets.size() > 0) {
    WriteMatrix(g.get(), "rotation_offsets", m.rotation_offsets, where, object + "/rotation_offsets");
  }

  const std::string po = object + "/rest_pose";
  Handle pg = h5::CreateGroup(g.get(), "rest_pose", where, po);
  WriteMatrix(pg.get(), "rotation", m.rest_pose.rotation, where, po + "/rotation");
  WriteVector(pg.get(), "translation", Eigen::VectorXd(m.rest_pose.translation), where, po + "/translation");

  const std::string so = object + "/shape";
  Handle sg = h5::CreateGroup(g.get(), "shape", where, so);
  h5::WriteAttr(sg.get(), "residual_variance", m.shape.residual_variance, where, so);
  WriteVector(sg.get(), "mean", m.shape.mean, where, so + "/mean");
  WriteMatrix(sg.get(), "loadings", m.shape.loadings, where, so + "/loadings");
  h5::WriteStrings(sg.get(), "parameter_names", m.shape.parameter_names, where, so + "/parameter_names");
  WriteVector(sg.get(), "variance_explained", m.shape.variance_explained, where, so + "/variance_explained");
  Handle steps = h5::CreateGroup(sg.get(), "steps", where, so + "/steps");
  for (size_t i = 0; i < m.shape.steps.size(); ++i) {
    const GuidedPcaStep& step = m.shape.steps[i];
    const std::string sto = so + "/steps/" + IndexName(i);
    Handle st = h5::CreateGroup(steps.get(), IndexName(i), where, sto);
    h5::WriteAttr(st.get(), "name", step.name, where, sto);
    h5::WriteAttr(st.get(), "components", int64_t{step.components}, where, sto);
    WriteIndices(st.get(), "markers", step.markers, where, sto + "/markers");
  }
}

void WriteHand(hid_t parent, const HandModel& m, const Where& where) {
  const std::string object = std::string("/") + kHandGroup;
  Handle g = h5::CreateGroup(parent, kHandGroup, where, object);
  WriteInfo(g.get(), m.info, where, object);

  const std::string lo = object + "/layout";
  Handle lg = h5::CreateGroup(g.get(), "layout", where, lo);
  h5::WriteStrings(lg.get(), "forearm", m.layout.forearm, where, lo + "/forearm");
  h5::WriteStrings(lg.get(), "hand", m.layout.hand, where, lo + "/hand");
  Handle segs = h5::CreateGroup(lg.get(), "segments", where, lo + "/segments");
  for (size_t i = 0; i < m.layout.segments.size(); ++i) {
    const HandSegmentDef& s = m.layout.segments[i];
    const std::string sto = lo + "/segments/" + IndexName(i);
    Handle st = h5::CreateGroup(segs.get(), IndexName(i), where, sto);
    h5::WriteAttr(st.get(), "name", s.name, where, sto);
    h5::WriteAttr(st.get(), "parent", int64_t{s.parent}, where, sto);
    WriteIndices(st.get(), "markers", s.markers, where, sto + "/markers");
  }

  // Rest orientations: [segments][3][3], each matrix row by row.
  std::vector<double> rest;
  rest.reserve(9 * m.rest.size());
  for (const Eigen::Matrix3d& r : m.rest) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) rest.push_back(r(i, j));
  }
  WriteArray(g.get(), "rest", {static_cast<hsize_t>(m.rest.size()), 3, 3}, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
             rest.data(), where, object + "/rest");
  WriteRigid(g.get(), "forearm", m.forearm, where, object + "/forearm");
  h5::WriteStrings(g.get(), "angle_names", m.angle_names, where, object + "/angle_names");
  WriteVector(g.get(), "param_scale", m.param_scale, where, object + "/param_scale");

  const std::string so = object + "/shape";
  Handle sg = h5::CreateGroup(g.get(), "shape", where, so);
  const std::string ao = so + "/angle_pca";
  Handle ag = h5::CreateGroup(sg.get(), "angle_pca", where, ao);
  const AnglePca& a = m.shape.angle_pca;
  WriteVector(ag.get(), "mean", a.mean, where, ao + "/mean");
  WriteMatrix(ag.get(), "components", a.components, where, ao + "/components");
  WriteVector(ag.get(), "variances", a.variances, where, ao + "/variances");
  WriteVector(ag.get(), "variance_explained", a.variance_explained, where, ao + "/variance_explained");
  const std::string ro = so + "/regression";
  Handle rg = h5::CreateGroup(sg.get(), "regression", where, ro);
  const HandRegression& r = m.shape.regression;
  h5::WriteAttr(rg.get(), "num_angles", int64_t{r.num_angles}, where, ro);
  h5::WriteAttr(rg.get(), "rank", int64_t{r.rank}, where, ro);
  h5::WriteAttr(rg.get(), "rms_residual", r.rms_residual, where, ro);
  WriteMatrix(rg.get(), "coefficients", r.coefficients, where, ro + "/coefficients");
  h5::WriteStrings(rg.get(), "warnings", r.warnings, where, ro + "/warnings");
  if (!m.fill.empty()) {
    const std::string fo = object + "/gaussian_fill";
    Handle fg = h5::CreateGroup(g.get(), "gaussian_fill", where, fo);
    h5::WriteAttr(fg.get(), "ridge_mm2", m.fill.ridge_mm2, where, fo);
    h5::WriteAttr(fg.get(), "frames", m.fill.frames, where, fo);
    h5::WriteAttr(fg.get(), "iterations", int64_t{m.fill.iterations}, where, fo);
    WriteVector(fg.get(), "mean", m.fill.mean, where, fo + "/mean");
    WriteMatrix(fg.get(), "covariance", m.fill.covariance, where, fo + "/covariance");
  }
}

// ---------------------------------------------------------------------------
// Reading. Structural problems (missing objects, wrong rank or type) are
// reported here; size consistency and values by the validators above.

Handle FileAccessList(const Where& where) {
  Handle fapl = h5::Own(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, where, "cannot create file access properties", "");
  // Structures readable by HDF5 1.8 (older MATLAB), as for the corpus.
  h5::Check(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V18, H5F_LIBVER_V18), where, "cannot set file format bounds",
            "");
  // Lock the file where the file system allows it, and still work where it
  // does not (some network file systems).
  h5::Check(H5Pset_file_locking(fapl.get(), true, true), where, "cannot set file locking", "");
  h5::Check(H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_SEMI), where, "cannot set close degree", "");
  return fapl;
}

Handle OpenGroupChecked(hid_t loc, const std::string& name, const std::string& object, const Checker& c) {
  if (!h5::LinkExists(loc, name)) c.Fail(object, "missing group");
  hid_t id = H5Gopen2(loc, name.c_str(), H5P_DEFAULT);
  if (id < 0) c.Fail(object, "is not a readable group (" + h5::TakeErrorMessage() + ")");
  return Handle(id, H5Gclose);
}

Handle OpenDatasetChecked(hid_t loc, const std::string& name, const std::string& object, const Checker& c) {
  if (!h5::LinkExists(loc, name)) c.Fail(object, "missing dataset");
  hid_t id = H5Dopen2(loc, name.c_str(), H5P_DEFAULT);
  if (id < 0) c.Fail(object, "is not a readable dataset (" + h5::TakeErrorMessage() + ")");
  return Handle(id, H5Dclose);
}

struct Numbers {
  std::vector<hsize_t> dims;
  std::vector<double> values;  // C order
};

Numbers ReadNumbers(hid_t loc, const std::string& name, size_t rank, const std::string& object, const Checker& c) {
  const Where& where = c.where();
  Handle ds = OpenDatasetChecked(loc, name, object, c);
  Handle type = h5::Own(H5Dget_type(ds.get()), H5Tclose, where, "cannot read the type of", object);
  H5T_class_t cls = H5Tget_class(type.get());
  if (cls != H5T_FLOAT && cls != H5T_INTEGER) c.Fail(object, "does not hold numbers");
  Handle space = h5::Own(H5Dget_space(ds.get()), H5Sclose, where, "cannot read the shape of", object);
  int r = H5Sget_simple_extent_ndims(space.get());
  if (r < 0) c.Fail(object, "has no readable shape");
  if (static_cast<size_t>(r) != rank) {
    c.Fail(object, "has rank " + Str(r) + ", expected " + Str(static_cast<int64_t>(rank)) +
                       (rank == 1   ? " (a vector)"
                        : rank == 2 ? " (a matrix)"
                                    : " (a stack of matrices)"));
  }
  Numbers out;
  out.dims.resize(rank);
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), out.dims.data(), nullptr);
  hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n < 0 || n > kMaxElements) c.Fail(object, "has an implausible size (" + Str(n) + " elements)");
  out.values.resize(static_cast<size_t>(n));
  if (n > 0) {
    h5::Check(H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.values.data()), where,
              "cannot read", object);
  }
  return out;
}

Eigen::VectorXd ReadVector(hid_t loc, const std::string& name, const std::string& object, const Checker& c) {
  Numbers n = ReadNumbers(loc, name, 1, object, c);
  return Eigen::Map<const Eigen::VectorXd>(n.values.data(), static_cast<Eigen::Index>(n.values.size()));
}

std::vector<double> ReadDoubleList(hid_t loc, const std::string& name, const std::string& object, const Checker& c) {
  return ReadNumbers(loc, name, 1, object, c).values;
}

Eigen::MatrixXd ReadMatrix(hid_t loc, const std::string& name, const std::string& object, const Checker& c) {
  Numbers n = ReadNumbers(loc, name, 2, object, c);
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  return Eigen::Map<const RowMajor>(n.values.data(), static_cast<Eigen::Index>(n.dims[0]),
                                    static_cast<Eigen::Index>(n.dims[1]));
}

Eigen::Matrix3Xd ReadPoints(hid_t loc, const std::string& name, const std::string& object, const Checker& c) {
  Numbers n = ReadNumbers(loc, name, 2, object, c);
  if (n.dims[1] != 3) {
    c.Fail(object, "has shape (" + Str(static_cast<int64_t>(n.dims[0])) + ", " + Str(static_cast<int64_t>(n.dims[1])) +
                       "), expected (points, 3)");
  }
  return Eigen::Map<const Eigen::Matrix3Xd>(n.values.data(), 3, static_cast<Eigen::Index>(n.dims[0]));
}

std::vector<int> ReadIndices(hid_t loc, const std::string& name, const std::string& object, const Checker& c) {
  Numbers n = ReadNumbers(loc, name, 1, object, c);
  std::vector<int> out;
  out.reserve(n.values.size());
  for (size_t i = 0; i < n.values.size(); ++i) {
    double v = n.values[i];
    if (!(v == std::floor(v) && std::abs(v) < 1e9)) {
      c.Fail(object, "value " + Num(v) + " at index " + Str(static_cast<int64_t>(i)) + " is not an integer index");
    }
    out.push_back(static_cast<int>(v));
  }
  return out;
}

std::vector<std::string> ReadStringList(hid_t loc, const std::string& name, const std::string& object,
                                        const Checker& c) {
  Handle ds = OpenDatasetChecked(loc, name, object, c);
  std::vector<hsize_t> dims = h5::Shape(ds.get(), c.where(), object);
  if (dims.size() != 1) c.Fail(object, "has rank " + Str(static_cast<int64_t>(dims.size())) + ", expected 1");
  ds.Reset();
  return h5::ReadStrings(loc, name, c.where(), object);
}

std::string RequiredStringAttr(hid_t obj, const std::string& name, const std::string& object, const Checker& c) {
  auto v = h5::ReadAttrString(obj, name, c.where(), object);
  if (!v) c.Fail(object, "missing attribute " + name);
  return *v;
}

double RequiredDoubleAttr(hid_t obj, const std::string& name, const std::string& object, const Checker& c) {
  auto v = h5::ReadAttrDouble(obj, name, c.where(), object);
  if (!v) c.Fail(object, "missing attribute " + name);
  return *v;
}

int RequiredIntAttr(hid_t obj, const std::string& name, const std::string& object, const Checker& c) {
  auto v = h5::ReadAttrDouble(obj, name, c.where(), object);
  if (!v) c.Fail(object, "missing attribute " + name);
  if (!(*v == std::floor(*v) && std::abs(*v) < 1e9)) {
    c.Fail(object, "attribute " + name + " (" + Num(*v) + ") is not an integer");
  }
  return static_cast<int>(*v);
}

ModelInfo ReadInfo(hid_t g, const std::string& object, const Checker& c) {
  // Provenance is optional: files written by other tools may leave it out.
  const Where& where = c.where();
  ModelInfo info;
  info.corpus = h5::ReadAttrString(g, "corpus", where, object).value_or("");
  info.training_takes = h5::ReadAttrStrings(g, "training_takes", where, object);
  info.config_json = h5::ReadAttrString(g, "config_json", where, object).value_or("");
  info.created_utc = h5::ReadAttrString(g, "created_utc", where, object).value_or("");
  info.csw_version = h5::ReadAttrString(g, "csw_version", where, object).value_or("");
  info.training_frames = h5::ReadAttrInt(g, "training_frames", where, object).value_or(0);
  info.selected_frames = h5::ReadAttrInt(g, "selected_frames", where, object).value_or(0);
  info.training_rms_mm = h5::ReadAttrDouble(g, "training_rms_mm", where, object).value_or(0.0);
  return info;
}

// Subgroups named 000, 001, ... in order; anything else is damage.
std::vector<std::string> IndexedGroups(hid_t g, const std::string& object, const Checker& c) {
  std::vector<std::string> names = h5::LinkNames(g, c.where(), object);
  std::vector<std::string> out(names.size());
  for (const std::string& n : names) {
    size_t i = 0;
    if (n.size() > 9) c.Fail(object, "unexpected member '" + n + "' (expected 000, 001, ...)");
    for (char ch : n) {
      if (ch < '0' || ch > '9') c.Fail(object, "unexpected member '" + n + "' (expected 000, 001, ...)");
      i = i * 10 + static_cast<size_t>(ch - '0');
    }
    if (n.empty() || i >= names.size() || !out[i].empty()) {
      c.Fail(object, "members are not numbered 000 to " + IndexName(names.size() - 1) + " ('" + n + "')");
    }
    out[i] = n;
  }
  return out;
}

RigidModel ReadRigid(hid_t parent, const std::string& name, const std::string& object, const Checker& c) {
  Handle g = OpenGroupChecked(parent, name, object, c);
  RigidModel m;
  m.name = h5::ReadAttrString(g.get(), "name", c.where(), object).value_or("");
  m.info = ReadInfo(g.get(), object, c);
  m.markers = ReadStringList(g.get(), "markers", object + "/markers", c);
  m.reference = ReadPoints(g.get(), "reference", object + "/reference", c);
  const std::string mo = object + "/motion";
  Handle mg = OpenGroupChecked(g.get(), "motion", mo, c);
  m.motion.total_variance = RequiredDoubleAttr(mg.get(), "total_variance", mo, c);
  m.motion.mean = ReadVector(mg.get(), "mean", mo + "/mean", c);
  m.motion.components = ReadMatrix(mg.get(), "components", mo + "/components", c);
  m.motion.variances = ReadVector(mg.get(), "variances", mo + "/variances", c);
  m.motion.explained_fraction = ReadVector(mg.get(), "explained_fraction", mo + "/explained_fraction", c);
  ValidateRigid(m, object, c);
  return m;
}

FaceModel ReadFace(hid_t parent, const Checker& c) {
  const std::string object = std::string("/") + kFaceGroup;
  Handle g = OpenGroupChecked(parent, kFaceGroup, object, c);
  FaceModel m;
  m.info = ReadInfo(g.get(), object, c);

  const std::string lo = object + "/layout";
  Handle lg = OpenGroupChecked(g.get(), "layout", lo, c);
  m.layout.head = ReadStringList(lg.get(), "head", lo + "/head", c);
  m.layout.face = ReadStringList(lg.get(), "face", lo + "/face", c);
  m.layout.throat = ReadStringList(lg.get(), "throat", lo + "/throat", c);
  m.layout.throat_weights = ReadDoubleList(lg.get(), "throat_weights", lo + "/throat_weights", c);

  m.head = ReadRigid(g.get(), "head", object + "/head", c);
  m.head_weights = ReadVector(g.get(), "head_weights", object + "/head_weights", c);
  // Optional (files written before the throat rotation offsets: all zero).
  if (h5::LinkExists(g.get(), "rotation_offsets")) {
    m.rotation_offsets = ReadMatrix(g.get(), "rotation_offsets", object + "/rotation_offsets", c);
  }

  const std::string po = object + "/rest_pose";
  Handle pg = OpenGroupChecked(g.get(), "rest_pose", po, c);
  Eigen::MatrixXd rot = ReadMatrix(pg.get(), "rotation", po + "/rotation", c);
  RequireShape(rot, 3, 3, po + "/rotation", "a rotation matrix", c);
  m.rest_pose.rotation = rot;
  Eigen::VectorXd tr = ReadVector(pg.get(), "translation", po + "/translation", c);
  RequireLength(tr.size(), 3, po + "/translation", "x y z in mm", c);
  m.rest_pose.translation = tr;

  const std::string so = object + "/shape";
  Handle sg = OpenGroupChecked(g.get(), "shape", so, c);
  m.shape.residual_variance = RequiredDoubleAttr(sg.get(), "residual_variance", so, c);
  m.shape.mean = ReadVector(sg.get(), "mean", so + "/mean", c);
  m.shape.loadings = ReadMatrix(sg.get(), "loadings", so + "/loadings", c);
  m.shape.parameter_names = ReadStringList(sg.get(), "parameter_names", so + "/parameter_names", c);
  m.shape.variance_explained = ReadDoubleList(sg.get(), "variance_explained", so + "/variance_explained", c);
  Handle steps = OpenGroupChecked(sg.get(), "steps", so + "/steps", c);
  for (const std::string& n : IndexedGroups(steps.get(), so + "/steps", c)) {
    const std::string sto = so + "/steps/" + n;
    Handle st = OpenGroupChecked(steps.get(), n, sto, c);
    GuidedPcaStep step;
    step.name = RequiredStringAttr(st.get(), "name", sto, c);
    step.components = RequiredIntAttr(st.get(), "components", sto, c);
    step.markers = ReadIndices(st.get(), "markers", sto + "/markers", c);
    m.shape.steps.push_back(std::move(step));
  }
  ValidateFace(m, object, c);
  return m;
}

HandModel ReadHand(hid_t parent, const Checker& c) {
  const std::string object = std::string("/") + kHandGroup;
  Handle g = OpenGroupChecked(parent, kHandGroup, object, c);
  HandModel m;
  m.info = ReadInfo(g.get(), object, c);

  const std::string lo = object + "/layout";
  Handle lg = OpenGroupChecked(g.get(), "layout", lo, c);
  m.layout.forearm = ReadStringList(lg.get(), "forearm", lo + "/forearm", c);
  m.layout.hand = ReadStringList(lg.get(), "hand", lo + "/hand", c);
  Handle segs = OpenGroupChecked(lg.get(), "segments", lo + "/segments", c);
  for (const std::string& n : IndexedGroups(segs.get(), lo + "/segments", c)) {
    const std::string sto = lo + "/segments/" + n;
    Handle st = OpenGroupChecked(segs.get(), n, sto, c);
    HandSegmentDef s;
    s.name = RequiredStringAttr(st.get(), "name", sto, c);
    s.parent = RequiredIntAttr(st.get(), "parent", sto, c);
    s.markers = ReadIndices(st.get(), "markers", sto + "/markers", c);
    m.layout.segments.push_back(std::move(s));
  }

  Numbers rest = ReadNumbers(g.get(), "rest", 3, object + "/rest", c);
  if (rest.dims[1] != 3 || rest.dims[2] != 3) {
    c.Fail(object + "/rest", "has shape (" + Str(static_cast<int64_t>(rest.dims[0])) + ", " +
                                 Str(static_cast<int64_t>(rest.dims[1])) + ", " +
                                 Str(static_cast<int64_t>(rest.dims[2])) + "), expected (segments, 3, 3)");
  }
  for (hsize_t i = 0; i < rest.dims[0]; ++i) {
    using RowMajor3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
    m.rest.push_back(Eigen::Map<const RowMajor3>(rest.values.data() + 9 * i));
  }
  m.forearm = ReadRigid(g.get(), "forearm", object + "/forearm", c);
  m.angle_names = ReadStringList(g.get(), "angle_names", object + "/angle_names", c);
  m.param_scale = ReadVector(g.get(), "param_scale", object + "/param_scale", c);

  const std::string so = object + "/shape";
  Handle sg = OpenGroupChecked(g.get(), "shape", so, c);
  const std::string ao = so + "/angle_pca";
  Handle ag = OpenGroupChecked(sg.get(), "angle_pca", ao, c);
  AnglePca& a = m.shape.angle_pca;
  a.mean = ReadVector(ag.get(), "mean", ao + "/mean", c);
  a.components = ReadMatrix(ag.get(), "components", ao + "/components", c);
  a.variances = ReadVector(ag.get(), "variances", ao + "/variances", c);
  a.variance_explained = ReadDoubleList(ag.get(), "variance_explained", ao + "/variance_explained", c);
  const std::string ro = so + "/regression";
  Handle rg = OpenGroupChecked(sg.get(), "regression", ro, c);
  HandRegression& r = m.shape.regression;
  r.num_angles = RequiredIntAttr(rg.get(), "num_angles", ro, c);
  r.rank = RequiredIntAttr(rg.get(), "rank", ro, c);
  r.rms_residual = RequiredDoubleAttr(rg.get(), "rms_residual", ro, c);
  r.coefficients = ReadMatrix(rg.get(), "coefficients", ro + "/coefficients", c);
  r.warnings = ReadStringList(rg.get(), "warnings", ro + "/warnings", c);
  if (h5::LinkExists(g.get(), "gaussian_fill")) {
    const std::string fo = object + "/gaussian_fill";
    Handle fg = OpenGroupChecked(g.get(), "gaussian_fill", fo, c);
    m.fill.ridge_mm2 = RequiredDoubleAttr(fg.get(), "ridge_mm2", fo, c);
    m.fill.frames = RequiredIntAttr(fg.get(), "frames", fo, c);
    m.fill.iterations = static_cast<int>(RequiredIntAttr(fg.get(), "iterations", fo, c));
    m.fill.mean = ReadVector(fg.get(), "mean", fo + "/mean", c);
    m.fill.covariance = ReadMatrix(fg.get(), "covariance", fo + "/covariance", c);
  }
  ValidateHand(m, object, c);
  return m;
}

// ---------------------------------------------------------------------------
// The key model /keys (analysis/keys/key_model.h)

void ValidateGaussians(const keys::GaussianClassifier& g, int labels, int dims, const std::string& object,
                       const Checker& c) {
  c.Require(g.num_labels() == labels, object, "has " + Str(g.num_labels()) + " labels, expected " + Str(labels));
  RequireLength(static_cast<int64_t>(g.feature_names().size()), dims, object + "/feature_names", "the model's features",
                c);
  c.Require(!g.classes().empty(), object, "has no class");
  for (const auto& k : g.classes()) {
    c.Require(k.label >= 0 && k.label < labels, object + "/labels", "label " + Str(k.label) + " out of range");
    RequireFinite(k.mean, object + "/means", c);
    RequireFinite(k.covariance, object + "/covariances", c);
    c.Require(k.prior > 0 && k.prior <= 1, object + "/priors", "prior " + Num(k.prior) + " outside (0, 1]");
    c.Require(k.count >= 0, object + "/counts", "negative count");
  }
}

void ValidateKeys(const keys::KeyModel& m, const std::string& object, const Checker& c) {
  ValidateInfo(m.info, object, c);
  ValidateGaussians(m.shape, keys::kNumShapes, keys::kNumDistances, object + "/shape", c);
  ValidateGaussians(m.placement, keys::kNumPlacements, 3, object + "/placement", c);
  const std::string reason = m.layout.Check();
  if (!reason.empty()) c.Fail(object + "/layout", reason);
  c.Require(m.head_reference.cols() == static_cast<Eigen::Index>(m.layout.head.size()), object + "/head_reference",
            "has " + Str(m.head_reference.cols()) + " points, the layout " +
                Str(static_cast<int64_t>(m.layout.head.size())) + " head markers");
  RequireFinite(m.head_reference, object + "/head_reference", c);
  for (int s : m.index_shapes)
    c.Require(s >= 0 && s < keys::kNumShapes, object + "/index_shapes", "shape " + Str(s) + " out of 0-8");
}

void WriteGaussians(hid_t parent, const std::string& name, const keys::GaussianClassifier& g, const Where& where,
                    const std::string& object) {
  Handle gr = h5::CreateGroup(parent, name, where, object);
  const auto& o = g.options();
  h5::WriteAttr(gr.get(), "num_labels", int64_t{g.num_labels()}, where, object);
  h5::WriteAttr(gr.get(), "shrinkage_samples", o.shrinkage_samples, where, object);
  h5::WriteAttr(gr.get(), "ridge_fraction", o.ridge_fraction, where, object);
  h5::WriteAttr(gr.get(), "min_variance", o.min_variance, where, object);
  h5::WriteAttr(gr.get(), "priors", std::string(keys::PriorKindName(o.priors)), where, object);
  h5::WriteStrings(gr.get(), "feature_names", g.feature_names(), where, object + "/feature_names");
  const auto k = static_cast<hsize_t>(g.classes().size());
  const auto d = static_cast<hsize_t>(g.dims());
  std::vector<std::string> names;
  std::vector<int64_t> labels, counts;
  std::vector<double> priors, means, covs;
  for (const auto& c : g.classes()) {
    names.push_back(c.name);
    labels.push_back(c.label);
    counts.push_back(c.count);
    priors.push_back(c.prior);
    for (Eigen::Index i = 0; i < c.mean.size(); ++i) means.push_back(c.mean(i));
    for (Eigen::Index i = 0; i < c.covariance.rows(); ++i)
      for (Eigen::Index j = 0; j < c.covariance.cols(); ++j) covs.push_back(c.covariance(i, j));
  }
  h5::WriteStrings(gr.get(), "class_names", names, where, object + "/class_names");
  WriteArray(gr.get(), "labels", {k}, H5T_STD_I64LE, H5T_NATIVE_INT64, labels.data(), where, object + "/labels");
  WriteArray(gr.get(), "counts", {k}, H5T_STD_I64LE, H5T_NATIVE_INT64, counts.data(), where, object + "/counts");
  WriteVector(gr.get(), "priors", priors, where, object + "/priors");
  WriteArray(gr.get(), "means", {k, d}, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, means.data(), where, object + "/means");
  WriteArray(gr.get(), "covariances", {k, d, d}, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, covs.data(), where,
             object + "/covariances");
}

void WriteKeys(hid_t parent, const keys::KeyModel& m, const Where& where) {
  const std::string object = std::string("/") + kKeysGroup;
  Handle g = h5::CreateGroup(parent, kKeysGroup, where, object);
  h5::WriteAttr(g.get(), "version", int64_t{keys::KeyModel::kVersion}, where, object);
  WriteInfo(g.get(), m.info, where, object);
  WriteIndices(g.get(), "index_shapes", m.index_shapes, where, object + "/index_shapes");
  const std::string lo = object + "/layout";
  Handle lg = h5::CreateGroup(g.get(), "layout", where, lo);
  h5::WriteAttr(lg.get(), "thumb_palm", m.layout.thumb_palm, where, lo);
  h5::WriteStrings(lg.get(), "proximal", {m.layout.proximal.begin(), m.layout.proximal.end()}, where, lo + "/proximal");
  h5::WriteStrings(lg.get(), "distal", {m.layout.distal.begin(), m.layout.distal.end()}, where, lo + "/distal");
  h5::WriteStrings(lg.get(), "palm", m.layout.palm, where, lo + "/palm");
  h5::WriteStrings(lg.get(), "head", m.layout.head, where, lo + "/head");
  WritePoints(g.get(), "head_reference", m.head_reference, where, object + "/head_reference");
  WriteGaussians(g.get(), "shape", m.shape, where, object + "/shape");
  WriteGaussians(g.get(), "placement", m.placement, where, object + "/placement");
}

keys::GaussianClassifier ReadGaussians(hid_t parent, const std::string& name, const std::string& object,
                                       const Checker& c) {
  Handle g = OpenGroupChecked(parent, name, object, c);
  keys::GaussianOptions o;
  const int labels = RequiredIntAttr(g.get(), "num_labels", object, c);
  o.shrinkage_samples = RequiredDoubleAttr(g.get(), "shrinkage_samples", object, c);
  o.ridge_fraction = RequiredDoubleAttr(g.get(), "ridge_fraction", object, c);
  o.min_variance = RequiredDoubleAttr(g.get(), "min_variance", object, c);
  const std::string priors = RequiredStringAttr(g.get(), "priors", object, c);
  if (!keys::ParsePriorKind(priors, &o.priors)) c.Fail(object, "attribute priors is '" + priors + "'");
  const auto features = ReadStringList(g.get(), "feature_names", object + "/feature_names", c);
  const auto names = ReadStringList(g.get(), "class_names", object + "/class_names", c);
  const auto label_list = ReadIndices(g.get(), "labels", object + "/labels", c);
  const auto counts = ReadDoubleList(g.get(), "counts", object + "/counts", c);
  const auto prior_list = ReadDoubleList(g.get(), "priors", object + "/priors", c);
  const Numbers means = ReadNumbers(g.get(), "means", 2, object + "/means", c);
  const Numbers covs = ReadNumbers(g.get(), "covariances", 3, object + "/covariances", c);
  const size_t k = names.size(), d = features.size();
  RequireLength(static_cast<int64_t>(label_list.size()), static_cast<int64_t>(k), object + "/labels", "one per class",
                c);
  RequireLength(static_cast<int64_t>(counts.size()), static_cast<int64_t>(k), object + "/counts", "one per class", c);
  RequireLength(static_cast<int64_t>(prior_list.size()), static_cast<int64_t>(k), object + "/priors", "one per class",
                c);
  c.Require(means.dims[0] == k && means.dims[1] == d, object + "/means", "expected (classes, features)");
  c.Require(covs.dims[0] == k && covs.dims[1] == d && covs.dims[2] == d, object + "/covariances",
            "expected (classes, features, features)");
  std::vector<keys::GaussianClass> classes(k);
  for (size_t i = 0; i < k; ++i) {
    auto& cl = classes[i];
    cl.name = names[i];
    cl.label = label_list[i];
    cl.count = static_cast<int64_t>(counts[i]);
    cl.prior = prior_list[i];
    cl.mean.resize(static_cast<Eigen::Index>(d));
    cl.covariance.resize(static_cast<Eigen::Index>(d), static_cast<Eigen::Index>(d));
    for (size_t a = 0; a < d; ++a) {
      cl.mean(static_cast<Eigen::Index>(a)) = means.values[i * d + a];
      for (size_t b = 0; b < d; ++b)
        cl.covariance(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = covs.values[(i * d + a) * d + b];
    }
    RequireFinite(cl.mean, object + "/means", c);
    RequireFinite(cl.covariance, object + "/covariances", c);
  }
  try {
    return keys::GaussianClassifier::FromClasses(std::move(classes), labels, features, o);
  } catch (const InvalidInput& e) {
    // A covariance that is not positive definite: name the dataset (docs/model-format.md).
    const bool covariance = std::string(e.what()).find("covariance") != std::string::npos;
    c.Fail(covariance ? object + "/covariances" : object, e.what());
  }
}

keys::KeyModel ReadKeys(hid_t parent, const Checker& c) {
  const std::string object = std::string("/") + kKeysGroup;
  Handle g = OpenGroupChecked(parent, kKeysGroup, object, c);
  const int version = RequiredIntAttr(g.get(), "version", object, c);
  if (version > keys::KeyModel::kVersion)
    c.Fail(object, "key model version " + Str(version) + " is newer than this csw reads (" +
                       Str(keys::KeyModel::kVersion) + ")");
  keys::KeyModel m;
  m.info = ReadInfo(g.get(), object, c);
  m.index_shapes = ReadIndices(g.get(), "index_shapes", object + "/index_shapes", c);
  const std::string lo = object + "/layout";
  Handle lg = OpenGroupChecked(g.get(), "layout", lo, c);
  m.layout.thumb_palm = h5::ReadAttrString(lg.get(), "thumb_palm", c.where(), lo).value_or("");
  const auto prox = ReadStringList(lg.get(), "proximal", lo + "/proximal", c);
  const auto dist = ReadStringList(lg.get(), "distal", lo + "/distal", c);
  RequireLength(static_cast<int64_t>(prox.size()), keys::kNumFingers, lo + "/proximal", "one per finger", c);
  RequireLength(static_cast<int64_t>(dist.size()), keys::kNumFingers, lo + "/distal", "one per finger", c);
  std::copy(prox.begin(), prox.end(), m.layout.proximal.begin());
  std::copy(dist.begin(), dist.end(), m.layout.distal.begin());
  m.layout.palm = ReadStringList(lg.get(), "palm", lo + "/palm", c);
  m.layout.head = ReadStringList(lg.get(), "head", lo + "/head", c);
  m.head_reference = ReadPoints(g.get(), "head_reference", object + "/head_reference", c);
  m.shape = ReadGaussians(g.get(), "shape", object + "/shape", c);
  m.placement = ReadGaussians(g.get(), "placement", object + "/placement", c);
  ValidateKeys(m, object, c);
  return m;
}

// Opens an existing file for reading. IoError when it cannot be read at all,
// ParseError when it is not (readable) HDF5.
Handle OpenForRead(const std::string& path, const Checker& c) {
  const Where& where = c.where();
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path, "no such file");
  if (fs::is_directory(path, ec)) throw IoError(path, "is a directory, not a model file");
  if (::access(path.c_str(), R_OK) != 0) throw IoError(path, "cannot read: " + Errno());
  htri_t is_hdf5 = H5Fis_hdf5(path.c_str());
  if (is_hdf5 == 0) {
    h5::TakeErrorMessage();
    c.Fail("", "not an HDF5 file (no HDF5 signature), so not a csw model file");
  }
  if (is_hdf5 < 0) throw IoError(path, "cannot read as HDF5: " + h5::TakeErrorMessage());
  Handle fapl = FileAccessList(where);
  hid_t id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get());
  if (id < 0) c.Fail("", "damaged or truncated HDF5 file: " + h5::TakeErrorMessage());
  return Handle(id, H5Fclose);
}

ModelFile Parse(hid_t file, const Checker& c) {
  const Where& where = c.where();
  auto format = h5::ReadAttrString(file, "format", where, "/");
  if (!format) c.Fail("", "not a csw model file: the root group has no 'format' attribute");
  if (*format == kCorpusFormatName) {
    c.Fail("", "this is a csw corpus (format 'csw-corpus'), not a model file (format 'csw-models')");
  }
  if (*format != kFormatName) c.Fail("", "not a csw model file: format is '" + *format + "', not 'csw-models'");
  auto version = h5::ReadAttrInt(file, "format_version", where, "/");
  if (!version) c.Fail("", "csw model file without a format_version attribute");
  if (*version > kModelFormatVersion) {
    c.Fail("", "model format_version " + Str(*version) + " is newer than this csw reads (" + Str(kModelFormatVersion) +
                   "); update csw");
  }
  if (*version < 1) c.Fail("", "invalid model format_version " + Str(*version));

  ModelFile out;
  if (h5::LinkExists(file, kHeadGroup)) out.head = ReadRigid(file, kHeadGroup, std::string("/") + kHeadGroup, c);
  if (h5::LinkExists(file, kForearmGroup)) {
    out.forearm = ReadRigid(file, kForearmGroup, std::string("/") + kForearmGroup, c);
  }
  if (h5::LinkExists(file, kFaceGroup)) out.face = ReadFace(file, c);
  if (h5::LinkExists(file, kHandGroup)) out.hand = ReadHand(file, c);
  if (h5::LinkExists(file, kKeysGroup)) out.keys = ReadKeys(file, c);
  return out;
}

// "path: message" → "message".
std::string StripFile(const std::string& message, const std::string& path) {
  const std::string prefix = path + ": ";
  if (message.compare(0, prefix.size(), prefix) == 0) return message.substr(prefix.size());
  return message;
}

// Refuses to replace an existing file that is not a csw model file (a corpus
// given as -o by mistake must survive).
void RefuseToClobber(const std::string& path) {
  std::error_code ec;
  fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) return;
  if (fs::is_directory(st)) throw IoError(path, "is a directory, not a model file");
  if (!fs::is_regular_file(st)) throw IoError(path, "exists and is not a regular file; not replacing it");
  if (fs::file_size(path, ec) == 0 && !ec) return;
  const std::string refuse = "refusing to replace it: ";
  htri_t is_hdf5 = H5Fis_hdf5(path.c_str());
  if (is_hdf5 <= 0) {
    h5::TakeErrorMessage();
    throw IoError(path, refuse + "it is not an HDF5 file, so not a csw model file (remove it first)");
  }
  Where where{path};
  Handle fapl = FileAccessList(where);
  hid_t id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, fapl.get());
  if (id < 0) {
    std::string detail = h5::TakeErrorMessage();
    throw IoError(path, refuse + "it is an HDF5 file that cannot be opened (" + detail + "); remove it first");
  }
  Handle file(id, H5Fclose);
  std::optional<std::string> format;
  try {
    format = h5::ReadAttrString(file.get(), "format", where, "/");
  } catch (const Error&) {
    format.reset();
  }
  if (!format || *format != kFormatName) {
    std::string what =
        !format ? "an HDF5 file without a csw format attribute"
                : "an HDF5 file of format '" + *format + "'" + (*format == kCorpusFormatName ? " (a csw corpus)" : "");
    throw IoError(path, refuse + "it is " + what + ", not a csw model file");
  }
}

// Removes the temporary file unless the save went through.
struct TempFile {
  std::string path;
  bool keep = false;
  ~TempFile() {
    if (!keep) ::unlink(path.c_str());
  }
};

}  // namespace

std::string ModelFileTempPath(const std::string& path) {
  fs::path p(path);
  return (p.parent_path() / ("." + p.filename().string() + ".csw-tmp." + std::to_string(::getpid()))).string();
}

ModelFile LoadModelFile(const std::string& path) {
  auto lock = h5::Lock();
  Checker c(path, true);
  Handle file = OpenForRead(path, c);
  try {
    return Parse(file.get(), c);
  } catch (const IoError& e) {
    // The file opened, so a failing read means damage inside it.
    throw ParseError({path, std::nullopt, std::nullopt}, "damaged model file: " + StripFile(e.what(), path));
  }
}

namespace {

// SaveModelFile without the writer lock (the caller holds it).
void SaveModelFileLocked(const std::string& path, const ModelFile& models) {
  Checker c(path, false);
  if (models.head) ValidateRigid(*models.head, std::string("/") + kHeadGroup, c);
  if (models.forearm) ValidateRigid(*models.forearm, std::string("/") + kForearmGroup, c);
  if (models.face) ValidateFace(*models.face, std::string("/") + kFaceGroup, c);
  if (models.hand) ValidateHand(*models.hand, std::string("/") + kHandGroup, c);
  if (models.keys) ValidateKeys(*models.keys, std::string("/") + kKeysGroup, c);

  auto lock = h5::Lock();
  RefuseToClobber(path);
  const Where& where = c.where();
  TempFile temp{ModelFileTempPath(path)};
  {
    // The caller holds the writer lock: temporary files of other processes
    // are left by killed writers.
    const fs::path p(path);
    const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    const std::string prefix = "." + p.filename().string() + ".csw-tmp.";
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string name = e.path().filename().string();
      if (name.compare(0, prefix.size(), prefix) == 0 && e.path() != fs::path(temp.path) && e.is_regular_file(ec)) {
        fs::remove(e.path(), ec);
      }
    }
  }
  {
    Handle fapl = FileAccessList(where);
    Handle file = h5::Own(H5Fcreate(temp.path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose, where,
                          "cannot create the temporary file", temp.path);
    hid_t f = file.get();
    h5::WriteAttr(f, "format", std::string(kFormatName), where, "/");
    h5::WriteAttr(f, "format_version", int64_t{kModelFormatVersion}, where, "/");
    h5::WriteAttr(f, "csw_version", std::string(CSW_VERSION), where, "/");
    h5::WriteAttr(f, "created_utc", UtcNow(), where, "/");
    if (models.head) WriteRigid(f, kHeadGroup, *models.head, where, std::string("/") + kHeadGroup);
    if (models.forearm) WriteRigid(f, kForearmGroup, *models.forearm, where, std::string("/") + kForearmGroup);
    if (models.face) WriteFace(f, *models.face, where);
    if (models.hand) WriteHand(f, *models.hand, where);
    if (models.keys) WriteKeys(f, *models.keys, where);
    h5::Check(H5Fflush(f, H5F_SCOPE_GLOBAL), where, "cannot flush", temp.path);
    if (!file.Reset()) throw IoError(path, "cannot close " + temp.path + ": " + h5::TakeErrorMessage());
  }
  ReplaceFileDurably(temp.path, path);
  temp.keep = true;
}

}  // namespace

void SaveModelFile(const std::string& path, const ModelFile& models) {
  if (path.empty()) throw IoError(path, "no output file name");
  // One writer at a time: a second `csw fit -o same.h5` gets a clear error.
  WriterLock writer(path, "model file");
  SaveModelFileLocked(path, models);
}

void UpdateModelFile(const std::string& path, const ModelFile& update) {
  if (path.empty()) throw IoError(path, "no output file name");
  // The lock covers the whole read-modify-write, so that two concurrent
  // updates cannot lose a model: the second one fails with the lock message.
  WriterLock writer(path, "model file");
  auto lock = h5::Lock();
  ModelFile models;
  std::error_code ec;
  // An empty file (e.g. made by mktemp) counts as no file.
  if (fs::exists(path, ec) && !(fs::is_regular_file(path, ec) && fs::file_size(path, ec) == 0)) {
    models = LoadModelFile(path);
  }
  if (update.head) models.head = update.head;
  if (update.forearm) models.forearm = update.forearm;
  if (update.face) models.face = update.face;
  if (update.hand) models.hand = update.hand;
  if (update.keys) models.keys = update.keys;
  SaveModelFileLocked(path, models);
}

}  // namespace csw
