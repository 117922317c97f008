#include "models/hand_model.h"

#include <ceres/tiny_solver.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <string>

#include "core/error.h"
#include "models/frame_selection.h"
#include "models/joint_angles.h"
#include "models/so3.h"

namespace csw {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------
// Segment frames and angles

// Frame of a segment with ≥ 3 markers (columns of `m`), see the header.
std::optional<Eigen::Matrix3d> PlaneFrame(const Eigen::Matrix3Xd& m) {
  if (!m.allFinite()) return std::nullopt;
  if (m.cols() == 3) {
    const auto f = FrameFromMarkers(m.col(0), m.col(1), m.col(2));
    if (!f) return std::nullopt;
    return f->rotation;
  }
  const Eigen::Vector3d ax = m.col(1) - m.col(0);
  const double ax_norm = ax.norm();
  if (!(ax_norm > 0)) return std::nullopt;
  const Eigen::Vector3d x = ax / ax_norm;
  const Eigen::Vector3d centroid = m.rowwise().mean();
  const Eigen::Matrix3Xd c = m.colwise() - centroid;
  const Eigen::Matrix3d scatter = c * c.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const Eigen::Vector3d lambda = eig.eigenvalues();  // ascending
  // Nearly collinear: the second axis carries no spread.
  if (!(lambda(1) > 1e-12 * lambda(2)) || !(lambda(2) > 0)) return std::nullopt;
  Eigen::Vector3d n = eig.eigenvectors().col(0);
  Eigen::Vector3d side = Eigen::Vector3d::Zero();
  for (Eigen::Index j = 2; j < m.cols(); ++j) side += m.col(j) - m.col(0);
  const Eigen::Vector3d orient = x.cross(side);
  if (!(orient.norm() > 1e-9 * side.norm())) return std::nullopt;
  if (n.dot(orient) < 0) n = -n;
  Eigen::Vector3d z = n - n.dot(x) * x;
  const double z_norm = z.norm();
  if (!(z_norm > 1e-9)) return std::nullopt;
  z /= z_norm;
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = z.cross(x);
  r.col(2) = z;
  return r;
}

// What the markers of one segment say, in its parent's frame: a direction
// (2 markers) or a relative rotation (≥ 3 markers).
struct SegmentObservation {
  bool ok = false;
  bool direction = false;
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rel = Eigen::Matrix3d::Identity();
};

SegmentObservation Observe(const HandSegmentDef& seg, const Eigen::Matrix3d& parent, const Eigen::Matrix3Xd& hand,
                           Eigen::Matrix3Xd* pts) {
  SegmentObservation o;
  pts->resize(3, static_cast<Eigen::Index>(seg.markers.size()));
  for (size_t j = 0; j < seg.markers.size(); ++j) pts->col(static_cast<Eigen::Index>(j)) = hand.col(seg.markers[j]);
  if (seg.markers.size() == 2) {
    if (!pts->allFinite()) return o;
    const Eigen::Vector3d d = parent.transpose() * (pts->col(1) - pts->col(0));
    const double len = d.norm();
    if (!(len > 0)) return o;
    o.u = d / len;
    o.direction = true;
    o.ok = true;
    return o;
  }
  const auto frame = PlaneFrame(*pts);
  if (!frame) return o;
  o.rel = parent.transpose() * *frame;
  o.ok = true;
  return o;
}

// Flexion and spread of a unit direction u = Ry(f)·Rz(s)·e_x (twist 0).
JointAngles DirectionAngles(const Eigen::Vector3d& u) {
  JointAngles ja;
  const double h = std::hypot(u(0), u(2));
  ja.spread = std::atan2(u(1), h);
  ja.flexion = h > 1e-12 ? std::atan2(-u(2), u(0)) : 0.0;
  ja.twist = 0;
  return ja;
}

// Angles and frame of a segment from its observation, its parent's frame and its rest.
void ApplyRest(const SegmentObservation& o, const Eigen::Matrix3d& parent, const Eigen::Matrix3d& rest, JointAngles* ja,
               Eigen::Matrix3d* rot) {
  if (o.direction) {
    *ja = DirectionAngles(rest.transpose() * o.u);
    *rot = parent * rest * RotationFromJointAngles(*ja);
  } else {
    *ja = JointAnglesFromRotation(rest.transpose() * o.rel);
    *rot = parent * o.rel;
  }
}

const Eigen::Matrix3d& RestOf(const std::vector<Eigen::Matrix3d>& rest, size_t s) {
  static const Eigen::Matrix3d kIdentity = Eigen::Matrix3d::Identity();
  return s < rest.size() ? rest[s] : kIdentity;
}

// Angles of every segment (3 each) into `angles`; `rotations` and `valid` are
// workspace (one per segment).
void SegmentAngles(const HandLayout& layout, const std::vector<Eigen::Matrix3d>& rest, const Eigen::Matrix3Xd& hand,
                   Eigen::VectorXd* angles, std::vector<Eigen::Matrix3d>* rotations, std::vector<uint8_t>* valid) {
  const size_t ns = layout.segments.size();
  angles->setConstant(static_cast<Eigen::Index>(3 * ns), kNaN);
  rotations->resize(ns);
  valid->assign(ns, 0);
  Eigen::Matrix3Xd pts;
  for (size_t s = 0; s < ns; ++s) {
    const HandSegmentDef& seg = layout.segments[s];
    Eigen::Matrix3d parent = Eigen::Matrix3d::Identity();
    if (seg.parent >= 0) {
      if (!(*valid)[static_cast<size_t>(seg.parent)]) continue;
      parent = (*rotations)[static_cast<size_t>(seg.parent)];
    }
    const SegmentObservation o = Observe(seg, parent, hand, &pts);
    if (!o.ok) continue;
    JointAngles ja;
    ApplyRest(o, parent, RestOf(rest, s), &ja, &(*rotations)[s]);
    (*valid)[s] = 1;
    (*angles)(static_cast<Eigen::Index>(3 * s)) = ja.flexion;
    (*angles)(static_cast<Eigen::Index>(3 * s + 1)) = ja.spread;
    (*angles)(static_cast<Eigen::Index>(3 * s + 2)) = ja.twist;
  }
}

// Rest orientation of every segment over some frames (hand markers in the
// forearm frame), parents first: the chordal mean of the relative rotations
// (≥ 3 markers) or Ry·Rz of the mean direction (2 markers).
std::vector<Eigen::Matrix3d> FitRests(const HandLayout& layout, const std::vector<Eigen::Matrix3Xd>& frames) {
  const size_t ns = layout.segments.size();
  const size_t nfr = frames.size();
  std::vector<Eigen::Matrix3d> rest(ns, Eigen::Matrix3d::Identity());
  std::vector<Eigen::Matrix3d> rot(nfr * ns, Eigen::Matrix3d::Identity());
  std::vector<uint8_t> valid(nfr * ns, 0);
  std::vector<SegmentObservation> obs(nfr);
  Eigen::Matrix3Xd pts;
  for (size_t s = 0; s < ns; ++s) {
    const HandSegmentDef& seg = layout.segments[s];
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    Eigen::Vector3d usum = Eigen::Vector3d::Zero();
    int64_t count = 0;
    for (size_t f = 0; f < nfr; ++f) {
      obs[f] = SegmentObservation();
      Eigen::Matrix3d parent = Eigen::Matrix3d::Identity();
      if (seg.parent >= 0) {
        const size_t pi = f * ns + static_cast<size_t>(seg.parent);
        if (!valid[pi]) continue;
        parent = rot[pi];
      }
      obs[f] = Observe(seg, parent, frames[f], &pts);
      if (!obs[f].ok) continue;
      ++count;
      if (obs[f].direction) {
        usum += obs[f].u;
      } else {
        sum += obs[f].rel;
      }
    }
    if (count > 0) {
      if (seg.markers.size() == 2) {
        if (usum.norm() > 0) rest[s] = RotationFromJointAngles(DirectionAngles(usum.normalized()));
      } else {
        Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
        Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
        if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) d(2, 2) = -1;
        rest[s] = svd.matrixU() * d * svd.matrixV().transpose();
      }
    }
    for (size_t f = 0; f < nfr; ++f) {
      if (!obs[f].ok) continue;
      const Eigen::Matrix3d parent =
          seg.parent >= 0 ? rot[f * ns + static_cast<size_t>(seg.parent)] : Eigen::Matrix3d::Identity();
      JointAngles ja;
      ApplyRest(obs[f], parent, rest[s], &ja, &rot[f * ns + s]);
      valid[f * ns + s] = 1;
    }
  }
  return rest;
}

// One frame of a marker array, columns [first, first + count), as doubles (NaN = missing).
void FrameColumns(const MarkerArray& m, int64_t frame, int64_t first, int64_t count, Eigen::Matrix3Xd* out) {
  out->resize(3, count);
  for (int64_t c = 0; c < count; ++c) {
    const float* p = m.at(frame, first + c);
    out->col(c) << p[0], p[1], p[2];
  }
}

MarkerArray Columns(const MarkerArray& m, int64_t first, int64_t count) {
  MarkerArray out(m.frames(), count);
  for (int64_t f = 0; f < m.frames(); ++f) std::copy(m.at(f, first), m.at(f, first) + 3 * count, out.at(f, 0));
  return out;
}

// ---------------------------------------------------------------------------
// Inversion

// The model's pieces in the form the solver uses (built once per InvertHand).
struct Kernel {
  int nf = 0, nh = 0, p = 0, na = 0;  // forearm markers, hand markers, parameters, active angles
  Eigen::Matrix3Xd reference;         // forearm cluster
  Eigen::VectorXd intercept;          // 3·nh
  Eigen::MatrixXd xcos_t, xsin_t;     // 3·nh × na
  Eigen::VectorXd mean;               // na
  Eigen::MatrixXd cs;                 // na × p: components · diag(scale)
  double prior = 0;
  double forearm_weight = 1;  // on the forearm cluster residuals (see the header)

  explicit Kernel(const HandModel& model, double prior_mm) {
    nf = static_cast<int>(model.forearm.reference.cols());
    nh = model.layout.num_shape_markers();
    p = model.num_parameters();
    reference = model.forearm.reference;
    const HandRegression& reg = model.shape.regression;
    const AnglePca& pca = model.shape.angle_pca;
    const int n = reg.num_angles;
    const Eigen::MatrixXd& x = reg.coefficients;
    intercept = x.row(0).transpose();
    // Angles whose cos and sin rows are both zero (dropped constant features,
    // or angles no component moves) add nothing: skip them.
    std::vector<int> active;
    for (int i = 0; i < n; ++i) {
      const bool used = x.row(1 + i).squaredNorm() > 0 || x.row(1 + n + i).squaredNorm() > 0;
      const bool moves = pca.components.row(i).squaredNorm() > 0;
      if (used && moves) {
        active.push_back(i);
      } else if (used) {
        // Constant angle: fold its features into the intercept.
        intercept +=
            std::cos(pca.mean(i)) * x.row(1 + i).transpose() + std::sin(pca.mean(i)) * x.row(1 + n + i).transpose();
      }
    }
    na = static_cast<int>(active.size());
    xcos_t.resize(3 * nh, na);
    xsin_t.resize(3 * nh, na);
    mean.resize(na);
    cs.resize(na, p);
    for (int k = 0; k < na; ++k) {
      const int i = active[static_cast<size_t>(k)];
      xcos_t.col(k) = x.row(1 + i).transpose();
      xsin_t.col(k) = x.row(1 + n + i).transpose();
      mean(k) = pca.mean(i);
      cs.row(k) = pca.components.row(i).cwiseProduct(model.param_scale.transpose());
    }
    prior = prior_mm;
    forearm_weight = kHandForearmWeight;
  }
};

// Per-solve state and scratch space (one per InvertHand call: not shared).
struct Workspace {
  Eigen::Matrix3Xd obs;          // 3 × (nf + nh), lab
  std::vector<uint8_t> visible;  // nf + nh
  Eigen::Matrix3d r0 = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t0 = Eigen::Vector3d::Zero();
  Eigen::VectorXd a, c, s, local;  // na, na, na, 3·nh
  Eigen::MatrixXd m, dlocal;       // 3·nh × na, 3·nh × p
};

// Local hand coordinates (forearm frame) for scaled parameters q.
void LocalCoordinates(const Kernel& k, const double* q, Workspace* w) {
  const Eigen::Map<const Eigen::VectorXd> qv(q, k.p);
  w->a.noalias() = k.cs * qv;
  w->a += k.mean;
  w->c = w->a.array().cos();
  w->s = w->a.array().sin();
  w->local = k.intercept;
  w->local.noalias() += k.xcos_t * w->c;
  w->local.noalias() += k.xsin_t * w->s;
}

// Parameters x = [δ (3), τ (3), q (p)]: R = exp(δ)·R0, t = t0 + τ, params = scale ⊙ q.
// Residuals: 3 per model marker (zero when not visible), then p prior rows.
struct HandResidual {
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = Eigen::Dynamic };

  const Kernel* k;
  Workspace* w;

  int NumResiduals() const { return 3 * (k->nf + k->nh) + k->p; }
  int NumParameters() const { return 6 + k->p; }

  bool operator()(const double* x, double* residuals, double* jacobian) const {
    const Eigen::Map<const Eigen::Vector3d> delta(x);
    const Eigen::Vector3d t = w->t0 + Eigen::Map<const Eigen::Vector3d>(x + 3);
    const Eigen::Matrix3d r = so3::Exp(delta) * w->r0;
    LocalCoordinates(*k, x + 6, w);
    const int nm = k->nf + k->nh;
    const int nr = NumResiduals();
    Eigen::Map<Eigen::VectorXd> res(residuals, nr);
    for (int j = 0; j < nm; ++j) {
      if (!w->visible[static_cast<size_t>(j)]) {
        res.segment<3>(3 * j).setZero();
        continue;
      }
      const Eigen::Vector3d local =
          j < k->nf ? Eigen::Vector3d(k->reference.col(j)) : Eigen::Vector3d(w->local.segment<3>(3 * (j - k->nf)));
      res.segment<3>(3 * j) = r * local + t - w->obs.col(j);
      if (j < k->nf) res.segment<3>(3 * j) *= k->forearm_weight;
    }
    for (int i = 0; i < k->p; ++i) res(3 * nm + i) = k->prior * x[6 + i];
    if (jacobian == nullptr) return true;

    Eigen::Map<Eigen::MatrixXd> jac(jacobian, nr, 6 + k->p);
    jac.setZero();
    const Eigen::Matrix3d jl = so3::LeftJacobian(delta);
    // d local / d q for every hand marker: (Xsinᵀ·diag(cos a) − Xcosᵀ·diag(sin a))·C·diag(scale).
    w->m.noalias() = k->xsin_t * w->c.asDiagonal();
    w->m.noalias() -= k->xcos_t * w->s.asDiagonal();
    w->dlocal.noalias() = w->m * k->cs;
    for (int j = 0; j < nm; ++j) {
      if (!w->visible[static_cast<size_t>(j)]) continue;
      const Eigen::Vector3d local =
          j < k->nf ? Eigen::Vector3d(k->reference.col(j)) : Eigen::Vector3d(w->local.segment<3>(3 * (j - k->nf)));
      if (j < k->nf) {
        jac.block<3, 3>(3 * j, 0).noalias() = -k->forearm_weight * so3::Hat(r * local) * jl;
        jac.block<3, 3>(3 * j, 3) = k->forearm_weight * Eigen::Matrix3d::Identity();
      } else {
        jac.block<3, 3>(3 * j, 0).noalias() = -so3::Hat(r * local) * jl;
        jac.block<3, 3>(3 * j, 3).setIdentity();
        jac.block(3 * j, 6, 3, k->p).noalias() = r * w->dlocal.middleRows(3 * (j - k->nf), 3);
      }
    }
    for (int i = 0; i < k->p; ++i) jac(3 * nm + i, 6 + i) = k->prior;
    return true;
  }
};

// Scaled parameters from joint angles, using the finite ones: least squares
// of componentsᵀ-space onto the measured deviations (exactly AnglePca::Params
// when every angle is known), with a small ridge.
Eigen::VectorXd ParamsFromAngles(const HandModel& model, const Eigen::VectorXd& angles) {
  const AnglePca& pca = model.shape.angle_pca;
  const int p = model.num_parameters();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(p);
  if (angles.allFinite()) {
    q = pca.Params(angles).cwiseQuotient(model.param_scale);
    return q;
  }
  Eigen::MatrixXd ata = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd atb = Eigen::VectorXd::Zero(p);
  int known = 0;
  for (Eigen::Index i = 0; i < angles.size(); ++i) {
    if (!std::isfinite(angles(i))) continue;
    const Eigen::RowVectorXd row = pca.components.row(i).cwiseProduct(model.param_scale.transpose());
    ata.noalias() += row.transpose() * row;
    atb += row.transpose() * WrapAngle(angles(i) - pca.mean(i));
    ++known;
  }
  if (known == 0) return q;
  ata.diagonal().array() += 1e-3 * (ata.trace() / p + 1e-12);
  q = ata.ldlt().solve(atb);
  if (!q.allFinite()) q.setZero();
  return q;
}

// The angle PCA weighted by each angle's effect on the markers (see
// HandModelOptions::weighted_angle_pca), then the regression on the angles it
// predicts, as FitHandShapeModel does.
HandShapeModel FitWeightedShapeModel(const Eigen::MatrixXd& angles, const Eigen::MatrixXd& coords, int k,
                                     const HandRegressionOptions& options) {
  const Eigen::Index n = angles.cols();
  const Eigen::Index frames = angles.rows();
  const HandRegression raw = FitHandRegression(angles, coords, options);
  const AnglePca full = FitAnglePca(angles, 1);  // its mean: circular mean + shift
  const double markers = static_cast<double>(coords.cols()) / 3.0;
  Eigen::VectorXd w(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double m = full.mean(i);
    w(i) = (-std::sin(m) * raw.coefficients.row(1 + i) + std::cos(m) * raw.coefficients.row(1 + n + i)).norm() /
           std::sqrt(markers);
  }
  const double floor = std::max(1e-12, 1e-6 * w.maxCoeff());
  for (Eigen::Index i = 0; i < n; ++i) w(i) = std::max(w(i), floor);
  Eigen::MatrixXd dev(frames, n);
  for (Eigen::Index f = 0; f < frames; ++f) {
    for (Eigen::Index i = 0; i < n; ++i) dev(f, i) = WrapAngle(angles(f, i) - full.mean(i));
  }
  dev.rowwise() -= dev.colwise().mean();
  const Eigen::MatrixXd z = dev * w.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(z.transpose() * z);
  Eigen::MatrixXd basis(n, k);
  for (int c = 0; c < k; ++c) basis.col(c) = w.cwiseInverse().asDiagonal() * eig.eigenvectors().col(n - 1 - c);
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(basis);
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(n, k);
  // Within the subspace: uncorrelated parameters, largest variance first.
  const Eigen::MatrixXd params = dev * q;
  const Eigen::MatrixXd cov = params.transpose() * params / static_cast<double>(frames - 1);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> e2(cov);
  const double total = (dev.transpose() * dev).trace() / static_cast<double>(frames - 1);
  HandShapeModel model;
  AnglePca& pca = model.angle_pca;
  pca.mean = full.mean;
  pca.components.resize(n, k);
  pca.variances.resize(k);
  for (int c = 0; c < k; ++c) {
    Eigen::VectorXd v = q * e2.eigenvectors().col(k - 1 - c);
    Eigen::Index big = 0;
    v.cwiseAbs().maxCoeff(&big);
    if (v(big) < 0) v = -v;  // deterministic sign
    pca.components.col(c) = v;
    pca.variances(c) = std::max(0.0, e2.eigenvalues()(k - 1 - c));
    pca.variance_explained.push_back(total > 0 ? pca.variances(c) / total : 0.0);
  }
  Eigen::MatrixXd predicted(frames, n);
  for (Eigen::Index f = 0; f < frames; ++f) {
    predicted.row(f) = pca.Angles(pca.Params(angles.row(f).transpose())).transpose();
  }
  model.regression = FitHandRegression(predicted, coords, options);
  return model;
}

}  // namespace

// ---------------------------------------------------------------------------

std::string CheckHandLayout(const HandLayout& layout) {
  const int nh = layout.num_shape_markers();
  if (layout.forearm.size() < 3) {
    return "the forearm cluster needs at least 3 markers (has " + std::to_string(layout.forearm.size()) + ")";
  }
  if (nh == 0) return "no hand markers";
  if (layout.segments.empty()) return "no hand segments";
  std::set<std::string> names;
  for (const auto& n : layout.forearm) {
    if (!names.insert(n).second) return "marker " + n + " appears twice";
  }
  for (const auto& n : layout.hand) {
    if (!names.insert(n).second) return "marker " + n + " appears twice";
  }
  std::set<std::string> segment_names;
  for (size_t s = 0; s < layout.segments.size(); ++s) {
    const HandSegmentDef& seg = layout.segments[s];
    const std::string where = "segment " + std::to_string(s) + " (" + seg.name + ")";
    if (!segment_names.insert(seg.name).second) return where + ": name used twice";
    if (seg.parent < -1 || seg.parent >= static_cast<int>(s)) {
      return where + ": parent " + std::to_string(seg.parent) +
             " must be -1 (forearm) or an earlier segment (parents come first)";
    }
    const size_t need = seg.parent < 0 ? 3 : 2;
    if (seg.markers.size() < need) {
      return where + ": has " + std::to_string(seg.markers.size()) + " markers, needs at least " +
             std::to_string(need) + (seg.parent < 0 ? " (a root segment defines its own frame)" : "");
    }
    std::set<int> seen;
    for (int m : seg.markers) {
      if (m < 0 || m >= nh) {
        return where + ": marker index " + std::to_string(m) + " outside 0.." + std::to_string(nh - 1);
      }
      if (!seen.insert(m).second) return where + ": marker " + layout.hand[static_cast<size_t>(m)] + " listed twice";
    }
  }
  return "";
}

Eigen::VectorXd HandModel::Angles(const Eigen::Matrix3Xd& hand_in_forearm) const {
  if (hand_in_forearm.cols() != layout.num_shape_markers()) {
    throw InvalidInput("hand model: Angles expects " + std::to_string(layout.num_shape_markers()) +
                       " hand markers, got " + std::to_string(hand_in_forearm.cols()));
  }
  if (!rest.empty() && rest.size() != layout.segments.size()) {
    throw InvalidInput("hand model: " + std::to_string(rest.size()) + " rest orientations for " +
                       std::to_string(layout.segments.size()) + " segments");
  }
  Eigen::VectorXd angles;
  std::vector<Eigen::Matrix3d> rotations;
  std::vector<uint8_t> valid;
  SegmentAngles(layout, rest, hand_in_forearm, &angles, &rotations, &valid);
  return angles;
}

Eigen::Matrix3Xd HandModel::ShapeMarkersInLab(const RigidTransform& pose, const Eigen::VectorXd& params) const {
  const Eigen::VectorXd local = shape.Predict(params);
  const Eigen::Index nh = layout.num_shape_markers();
  if (local.size() != 3 * nh) {
    throw InvalidInput("hand model: the shape model predicts " + std::to_string(local.size()) + " coordinates for " +
                       std::to_string(nh) + " hand markers");
  }
  Eigen::Matrix3Xd out(3, nh);
  for (Eigen::Index m = 0; m < nh; ++m) out.col(m) = pose.Apply(local.segment<3>(3 * m));
  return out;
}

Eigen::Matrix3Xd HandModel::MarkersInLab(const RigidTransform& pose, const Eigen::VectorXd& params) const {
  const Eigen::Index nf = forearm.reference.cols();
  const Eigen::Matrix3Xd hand = ShapeMarkersInLab(pose, params);
  Eigen::Matrix3Xd out(3, nf + hand.cols());
  for (Eigen::Index j = 0; j < nf; ++j) out.col(j) = pose.Apply(forearm.reference.col(j));
  out.rightCols(hand.cols()) = hand;
  return out;
}

HandModel FitHandModel(const HandLayout& layout, const std::vector<MarkerArray>& takes, const HandModelOptions& options,
                       Progress* progress) {
  const std::string bad = CheckHandLayout(layout);
  if (!bad.empty()) throw InvalidInput("hand model layout: " + bad);
  const int n_angles = 3 * static_cast<int>(layout.segments.size());
  if (options.angle_components < 1 || options.angle_components > n_angles) {
    throw InvalidInput("hand model: angle_components " + std::to_string(options.angle_components) + " outside 1.." +
                       std::to_string(n_angles) + " (3 angles per segment)");
  }
  if (!(options.min_distance_mm > 0)) throw InvalidInput("hand model: min_distance_mm must be > 0");
  if (takes.empty()) throw InvalidInput("hand model: no training take");
  const int64_t nf = static_cast<int64_t>(layout.forearm.size());
  const int64_t nh = layout.num_shape_markers();
  for (size_t i = 0; i < takes.size(); ++i) {
    if (takes[i].markers() != layout.num_markers()) {
      throw InvalidInput("hand model: training take " + std::to_string(i + 1) + " has " +
                         std::to_string(takes[i].markers()) + " columns, the layout has " +
                         std::to_string(layout.num_markers()) + " (" + std::to_string(nf) + " forearm + " +
                         std::to_string(nh) + " hand)");
    }
  }
  if (progress) progress->Update("hand model: forearm cluster", 0.0);

  HandModel model;
  model.layout = layout;
  {
    std::vector<MarkerArray> forearm_takes;
    forearm_takes.reserve(takes.size());
    for (const MarkerArray& t : takes) forearm_takes.push_back(Columns(t, 0, nf));
    model.forearm = FitRigidModel("forearm", layout.forearm, forearm_takes, options.forearm, progress);
  }

  // Hand markers in the forearm frame, frames with every hand marker visible.
  std::vector<int> forearm_columns(static_cast<size_t>(nf));
  for (int c = 0; c < static_cast<int>(nf); ++c) forearm_columns[static_cast<size_t>(c)] = c;
  std::vector<MarkerArray> local_takes;
  int64_t complete = 0;
  std::vector<Eigen::VectorXd> fill_rows;  // training frames of the Gaussian gap filler
  for (size_t i = 0; i < takes.size(); ++i) {
    if (progress)
      progress->Update("hand model: forearm frames", static_cast<double>(i) / static_cast<double>(takes.size()));
    const RigidSeries series =
        EstimateRigidSeries(takes[i], forearm_columns, model.forearm.reference, options.forearm.rigid, progress);
    const MarkerArray local = ToLocalFrame(Columns(takes[i], nf, nh), series);
    int64_t count = 0;
    std::vector<int64_t> keep;
    for (int64_t f = 0; f < local.frames(); ++f) {
      bool all = true;
      for (int64_t m = 0; m < nh && all; ++m) all = local.Visible(f, m);
      if (all) keep.push_back(f);
    }
    if (options.gaussian_fill) {
      int64_t last = -1;
      for (int64_t f = 0; f < local.frames(); ++f) {
        int64_t seen = 0;
        for (int64_t m = 0; m < nh; ++m) seen += local.Visible(f, m) ? 1 : 0;
        if (2 * seen < nh) continue;
        bool moved = last < 0;
        for (int64_t m = 0; m < nh && !moved; ++m) {
          if (!local.Visible(f, m) || !local.Visible(last, m)) continue;
          const float* a = local.at(f, m);
          const float* b = local.at(last, m);
          moved = std::hypot(double(a[0]) - b[0], double(a[1]) - b[1], double(a[2]) - b[2]) >= options.min_distance_mm;
        }
        if (!moved) continue;
        last = f;
        Eigen::VectorXd row(3 * nh);
        for (int64_t m = 0; m < nh; ++m) {
          const float* a = local.at(f, m);
          for (int k = 0; k < 3; ++k) row(3 * m + k) = IsMissing(a[0]) ? kNaN : double(a[k]);
        }
        fill_rows.push_back(std::move(row));
      }
    }
    count = static_cast<int64_t>(keep.size());
    MarkerArray kept(count, nh);
    for (int64_t r = 0; r < count; ++r) {
      std::copy(local.at(keep[static_cast<size_t>(r)], 0), local.at(keep[static_cast<size_t>(r)], 0) + 3 * nh,
                kept.at(r, 0));
    }
    complete += count;
    local_takes.push_back(std::move(kept));
  }
  if (complete < 2) {
    throw InvalidInput("hand model: " + std::to_string(complete) +
                       " training frames have every hand marker visible and a forearm pose (need at least 2)");
  }
  MarkerArray all(complete, nh);
  {
    int64_t at = 0;
    for (const MarkerArray& t : local_takes) {
      std::copy(t.data().begin(), t.data().end(), all.data().begin() + static_cast<std::ptrdiff_t>(at * nh * 3));
      at += t.frames();
    }
  }
  local_takes.clear();

  if (progress) progress->Update("hand model: training frames", 0.0);
  std::vector<int> hand_columns(static_cast<size_t>(nh));
  for (int c = 0; c < static_cast<int>(nh); ++c) hand_columns[static_cast<size_t>(c)] = c;
  const FrameSelection selection = SelectTrainingFrames(all, hand_columns, options.min_distance_mm);

  // Rest orientations, then joint angles of the selected frames; a degenerate
  // segment drops the frame.
  const auto selected = static_cast<int64_t>(selection.frames.size());
  std::vector<Eigen::Matrix3Xd> hands(static_cast<size_t>(selected));
  for (int64_t i = 0; i < selected; ++i) {
    FrameColumns(all, selection.frames[static_cast<size_t>(i)], 0, nh, &hands[static_cast<size_t>(i)]);
  }
  if (progress) progress->Update("hand model: joint angles", 0.0);
  model.rest = FitRests(layout, hands);
  Eigen::MatrixXd angles(selected, n_angles);
  Eigen::MatrixXd coords(selected, 3 * nh);
  Eigen::VectorXd a;
  std::vector<Eigen::Matrix3d> rotations;
  std::vector<uint8_t> valid;
  int64_t rows = 0;
  for (int64_t i = 0; i < selected; ++i) {
    if (progress && i % 1024 == 0) {
      progress->Update("hand model: joint angles", static_cast<double>(i) / static_cast<double>(selected));
    }
    const Eigen::Matrix3Xd& hand = hands[static_cast<size_t>(i)];
    SegmentAngles(layout, model.rest, hand, &a, &rotations, &valid);
    if (!a.allFinite()) continue;
    angles.row(rows) = a.transpose();
    coords.row(rows) = Eigen::Map<const Eigen::RowVectorXd>(hand.data(), 3 * nh);
    ++rows;
  }
  if (rows < options.angle_components + 1) {
    throw InvalidInput("hand model: " + std::to_string(rows) + " usable training frames (of " +
                       std::to_string(selected) + " selected, " + std::to_string(complete) + " complete) for " +
                       std::to_string(options.angle_components) + " angle components: need at least components + 1");
  }
  angles.conservativeResize(rows, Eigen::NoChange);
  coords.conservativeResize(rows, Eigen::NoChange);

  if (progress) progress->Update("hand model: regression", 0.0);
  for (const auto& seg : layout.segments) {
    for (const char* what : {"flexion", "spread", "twist"}) model.angle_names.push_back(seg.name + "." + what);
  }
  {
    // Rank of the training angles (eigenvalues of their covariance above 1e-12 of the total): parameters
    // beyond it have no variance (2-marker segments' twists are always 0, coupled joints move together).
    const AnglePca all = FitAnglePca(angles, static_cast<int>(angles.cols()));
    const double total = all.variances.sum();
    int rank = 0;
    for (Eigen::Index k = 0; k < all.variances.size(); ++k) rank += all.variances(k) > 1e-12 * total ? 1 : 0;
    if (options.angle_components > rank) {
      model.warnings.push_back("angle_components " + std::to_string(options.angle_components) +
                               " exceeds the rank of the training angles (" + std::to_string(rank) + " of " +
                               std::to_string(angles.cols()) + " angles vary independently): parameters " +
                               std::to_string(rank + 1) + ".." + std::to_string(options.angle_components) +
                               " have no variance; use at most " + std::to_string(rank));
    }
  }
  HandRegressionOptions regression = options.regression;
  regression.angle_names = model.angle_names;  // warnings name angles, not indices
  model.shape = options.weighted_angle_pca ? FitWeightedShapeModel(angles, coords, options.angle_components, regression)
                                           : FitHandShapeModel(angles, coords, options.angle_components, regression);
  const int p = model.num_parameters();
  model.param_scale.resize(p);
  for (int k = 0; k < p; ++k) {
    const double sd = std::sqrt(std::max(0.0, model.shape.angle_pca.variances(k)));
    model.param_scale(k) = sd > 1e-12 ? sd : 1.0;
  }
  // Fit residual (3D marker distance, RMS) over the frames used.
  double sum = 0;
  for (int64_t r = 0; r < rows; ++r) {
    const Eigen::VectorXd pred = model.shape.Predict(model.shape.angle_pca.Params(angles.row(r).transpose()));
    sum += (pred - coords.row(r).transpose()).squaredNorm();
  }
  if (options.gaussian_fill && fill_rows.size() >= 2) {
    Eigen::MatrixXd data(static_cast<Eigen::Index>(fill_rows.size()), 3 * nh);
    for (size_t r = 0; r < fill_rows.size(); ++r) data.row(static_cast<Eigen::Index>(r)) = fill_rows[r].transpose();
    fill_rows.clear();
    model.fill = FitGaussianFill(data, options.fill, progress);
  }
  model.info.training_frames = complete;
  model.info.selected_frames = rows;
  // training_rms_mm: what inverting the training frames reaches (the
  // regression at the PCA projection of each frame's measured angles, `sum`,
  // is not a fit to the markers: 2.76 mm on the virtual cuer where inverting
  // the same frames fits 0.37 mm). Each selected frame's hand markers, with
  // the forearm cluster at its reference, inverted from a cold start.
  const double regression_rms = std::sqrt(sum / static_cast<double>(rows * nh));
  model.info.training_rms_mm = regression_rms;  // the retry threshold of this solve only
  {
    MarkerArray frames(rows, nf + nh);
    for (int64_t r = 0; r < rows; ++r) {
      for (int64_t c = 0; c < nf; ++c) {
        for (int k = 0; k < 3; ++k) frames.at(r, c)[k] = static_cast<float>(model.forearm.reference(k, c));
      }
      for (int64_t c = 0; c < nh; ++c) {
        for (int k = 0; k < 3; ++k) frames.at(r, nf + c)[k] = static_cast<float>(coords(r, 3 * c + k));
      }
    }
    InversionOptions io;
    io.warm_start = false;
    io.gaussian_fill = false;
    const InversionResult fit = InvertHand(model, frames, io, progress);
    double s2 = 0;
    int64_t n = 0;
    for (int64_t f = 0; f < rows; ++f) {
      for (int64_t c = nf; c < nf + nh; ++c) {
        const double e = fit.error_mm(f, c);
        if (!std::isfinite(e)) continue;
        s2 += e * e;
        ++n;
      }
    }
    if (n > 0) model.info.training_rms_mm = std::sqrt(s2 / static_cast<double>(n));
  }
  if (progress) progress->Update("hand model: regression", 1.0);
  return model;
}

InversionResult InvertHand(const HandModel& model, const MarkerArray& take, const InversionOptions& options,
                           Progress* progress) {
  const int nf = static_cast<int>(model.forearm.reference.cols());
  const int nh = model.layout.num_shape_markers();
  const int nm = nf + nh;
  const int p = model.num_parameters();
  if (take.markers() != nm) {
    throw InvalidInput("hand inversion: the take has " + std::to_string(take.markers()) + " columns, the model has " +
                       std::to_string(nm) + " (" + std::to_string(nf) + " forearm + " + std::to_string(nh) + " hand)");
  }
  if (model.shape.regression.coefficients.cols() != 3 * nh || model.param_scale.size() != p ||
      model.shape.regression.num_angles != model.shape.angle_pca.mean.size()) {
    throw InvalidInput("hand inversion: the model is inconsistent (shape model, scales and layout disagree)");
  }
  if (!(options.prior_mm >= 0)) throw InvalidInput("hand inversion: prior_mm must be >= 0");
  const int64_t frames = take.frames();

  InversionResult out;
  out.pose.setConstant(frames, 6, kNaN);
  out.params.setConstant(frames, p, kNaN);
  out.reconstructed = MarkerArray(frames, nm);
  out.error_mm.setConstant(frames, nm, kNaN);
  out.ResizeFrames(frames);

  const Kernel kernel(model, options.prior_mm);
  Workspace w;
  w.obs.resize(3, nm);
  w.visible.assign(static_cast<size_t>(nm), 0);
  w.a.resize(kernel.na);
  w.c.resize(kernel.na);
  w.s.resize(kernel.na);
  w.local.resize(3 * nh);
  w.m.resize(3 * nh, kernel.na);
  w.dlocal.resize(3 * nh, p);
  const HandResidual residual{&kernel, &w};
  ceres::TinySolver<HandResidual> solver;
  solver.options.max_num_iterations = std::max(1, options.max_iterations);
  solver.options.gradient_tolerance = 1e-10;
  solver.options.parameter_tolerance = 1e-8;
  Eigen::VectorXd x(6 + p), x2(6 + p);
  Eigen::VectorXd res0(residual.NumResiduals());
  // Warm starts ending above this RMS (mm, per visible marker) are retried cold.
  const double retry_rms_mm = 3.0 * model.info.training_rms_mm + 1.0;
  Eigen::VectorXd q = Eigen::VectorXd::Zero(p);
  Eigen::Matrix3d r_prev = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_prev = Eigen::Vector3d::Zero();
  bool have_prev = false;
  Eigen::Matrix3Xd forearm_obs(3, nf);
  Eigen::Matrix3Xd hand_local(3, nh);
  std::optional<GaussianFiller> filler;
  if (options.gaussian_fill && !model.fill.empty()) {
    if (model.fill.markers() != nh) {
      throw InvalidInput("hand inversion: the model's gap filler has " + std::to_string(model.fill.markers()) +
                         " markers, the model " + std::to_string(nh));
    }
    filler.emplace(model.fill);
  }
  Eigen::Matrix3Xd fill_local(3, nh);

  for (int64_t f = 0; f < frames; ++f) {
    if (progress && f % 512 == 0)
      progress->Update("hand inversion", static_cast<double>(f) / static_cast<double>(frames));
    int vis_f = 0, vis_h = 0;
    for (int j = 0; j < nm; ++j) {
      const float* pt = take.at(f, j);
      const bool v = !IsMissing(pt[0]) && !IsMissing(pt[1]) && !IsMissing(pt[2]);
      w.visible[static_cast<size_t>(j)] = v ? 1 : 0;
      if (v) {
        w.obs.col(j) << pt[0], pt[1], pt[2];
        (j < nf ? vis_f : vis_h) += 1;
      } else {
        w.obs.col(j).setConstant(kNaN);
      }
    }
    if (vis_f < options.min_cluster_markers || vis_f < 3 || vis_h < options.min_shape_markers) {
      have_prev = false;
      continue;  // status kTooFewMarkers
    }
    int iterations = 0;  // of the last solve
    // One solve from the current start (w.r0, w.t0, q); returns the final cost.
    auto solve = [&](Eigen::VectorXd* xx, bool* conv) {
      xx->head<6>().setZero();
      xx->tail(p) = q;
      residual(xx->data(), res0.data(), nullptr);
      const double cost0 = 0.5 * res0.squaredNorm();
      solver.options.function_tolerance = 1e-7 * cost0 + 1e-14;
      const auto& summary = solver.Solve(residual, xx);
      *conv = summary.status != ceres::TinySolver<HandResidual>::HIT_MAX_ITERATIONS;
      iterations = summary.iterations;
      residual(xx->data(), res0.data(), nullptr);
      return xx->allFinite() ? 0.5 * res0.squaredNorm() : std::numeric_limits<double>::infinity();
    };
    auto cold_start = [&]() {
      // Kabsch on the forearm cluster, parameters from the measured angles.
      forearm_obs = w.obs.leftCols(nf);
      const RigidFit fit = EstimateRigidKabsch(kernel.reference, forearm_obs);
      if (!fit.valid) return false;
      w.r0 = fit.transform.rotation;
      w.t0 = fit.transform.translation;
      hand_local = fit.transform.rotation.transpose() * (w.obs.rightCols(nh).colwise() - fit.transform.translation);
      // Missing hand markers make their segments' angles unmeasurable; the gap
      // filler's conditional mean stands in for them (a start only: the solve
      // fits the seen markers).
      if (filler && vis_h < nh) filler->Fill(&hand_local);
      q = ParamsFromAngles(model, model.Angles(hand_local));
      return true;
    };
    bool conv = false;
    double cost = 0;
    const bool warm = options.warm_start && have_prev;
    bool kept_cold = !warm, retried = false;
    int kept_iterations = 0;
    if (warm) {
      w.r0 = r_prev;
      w.t0 = t_prev;
      cost = solve(&x, &conv);
      kept_iterations = iterations;
      // A warm start that ends far worse than the model's usual fit (a jump
      // in the data, a wrong local minimum): try a cold start, keep the better.
      const double rms = std::sqrt(2 * cost / std::max(1, vis_f + vis_h));
      if (!(rms <= retry_rms_mm)) {
        retried = true;
        const Eigen::Matrix3d r_warm = w.r0;
        const Eigen::Vector3d t_warm = w.t0;
        const Eigen::VectorXd q_warm = q;
        bool conv2 = false;
        double cost2 = std::numeric_limits<double>::infinity();
        if (cold_start()) cost2 = solve(&x2, &conv2);
        if (cost2 < cost) {
          x = x2;
          cost = cost2;
          conv = conv2;
          kept_cold = true;
          kept_iterations = iterations;
        } else {
          w.r0 = r_warm;
          w.t0 = t_warm;
          q = q_warm;
        }
      }
    } else {
      if (!cold_start()) {
        out.status[static_cast<size_t>(f)] = FrameStatus::kNoStart;
        have_prev = false;
        continue;
      }
      cost = solve(&x, &conv);
      kept_iterations = iterations;
    }
    // Still above the threshold (a cold start far from the answer, as in a
    // take's first frame, or both starts in wrong minima): two more starts,
    // the best kept: the solution so far continued for another
    // max_iterations, and the mean posture (q = 0) at the cluster's Kabsch pose.
    auto frame_rms = [&](double c) { return std::sqrt(2 * c / std::max(1, vis_f + vis_h)); };
    if (std::isfinite(cost) && x.allFinite() && !(frame_rms(cost) <= retry_rms_mm)) {
      retried = true;
      // The best so far as an absolute start (w.r0, w.t0, q; x = 0 relative).
      auto absolute = [&](const Eigen::VectorXd& xx) {
        w.r0 = Eigen::Quaterniond(so3::Exp(xx.head<3>()) * w.r0).normalized().toRotationMatrix();
        w.t0 = w.t0 + xx.segment<3>(3);
        q = xx.tail(p);
      };
      absolute(x);
      Eigen::Matrix3d best_r = w.r0;
      Eigen::Vector3d best_t = w.t0;
      Eigen::VectorXd best_q = q;
      bool conv2 = false;
      double cost2 = solve(&x2, &conv2);  // continued
      if (cost2 < cost) {
        absolute(x2);
        best_r = w.r0, best_t = w.t0, best_q = q;
        cost = cost2;
        conv = conv2;
        kept_iterations += iterations;
      }
      if (cold_start()) {
        q.setZero();
        cost2 = solve(&x2, &conv2);  // mean posture
        if (cost2 < cost) {
          absolute(x2);
          best_r = w.r0, best_t = w.t0, best_q = q;
          cost = cost2;
          conv = conv2;
          kept_cold = true;
          kept_iterations = iterations;
        }
      }
      w.r0 = best_r;
      w.t0 = best_t;
      q = best_q;
      x.head<6>().setZero();
      x.tail(p) = q;
    }
    out.cold_retry[static_cast<size_t>(f)] = retried ? 1 : 0;
    if (!x.allFinite() || !std::isfinite(cost)) {
      out.status[static_cast<size_t>(f)] = FrameStatus::kFailed;
      have_prev = false;
      continue;
    }
    const Eigen::Matrix3d r = Eigen::Quaterniond(so3::Exp(x.head<3>()) * w.r0).normalized().toRotationMatrix();
    const Eigen::Vector3d t = w.t0 + x.segment<3>(3);
    q = x.tail(p);
    r_prev = r;
    t_prev = t;
    have_prev = true;

    RigidTransform pose;
    pose.rotation = r;
    pose.translation = t;
    out.pose.row(f) = pose.Parameters().transpose();
    out.params.row(f) = q.cwiseProduct(model.param_scale).transpose();
    out.solved[static_cast<size_t>(f)] = 1;
    out.converged[static_cast<size_t>(f)] = conv ? 1 : 0;
    out.status[static_cast<size_t>(f)] = conv ? FrameStatus::kConverged : FrameStatus::kMaxIterations;
    out.iterations[static_cast<size_t>(f)] = kept_iterations;
    out.cold_start[static_cast<size_t>(f)] = kept_cold ? 1 : 0;
    LocalCoordinates(kernel, q.data(), &w);
    for (int j = 0; j < nm; ++j) {
      const Eigen::Vector3d lab = j < nf ? Eigen::Vector3d(r * kernel.reference.col(j) + t)
                                         : Eigen::Vector3d(r * w.local.segment<3>(3 * (j - nf)) + t);
      float* o = out.reconstructed.at(f, j);
      o[0] = static_cast<float>(lab(0));
      o[1] = static_cast<float>(lab(1));
      o[2] = static_cast<float>(lab(2));
      if (w.visible[static_cast<size_t>(j)]) out.error_mm(f, j) = (lab - w.obs.col(j)).norm();
    }
    if (filler && vis_h < nh) {
      // Hidden hand markers: the Gaussian filler's conditional mean given the
      // seen ones, in the solved forearm frame.
      for (int j = 0; j < nh; ++j) {
        fill_local.col(j) = w.visible[static_cast<size_t>(nf + j)]
                                ? Eigen::Vector3d(r.transpose() * (w.obs.col(nf + j) - t))
                                : Eigen::Vector3d::Constant(kNaN);
      }
      filler->Fill(&fill_local);
      for (int j = 0; j < nh; ++j) {
        if (w.visible[static_cast<size_t>(nf + j)] || !fill_local.col(j).allFinite()) continue;
        const Eigen::Vector3d lab = r * fill_local.col(j) + t;
        float* o = out.reconstructed.at(f, nf + j);
        o[0] = static_cast<float>(lab(0));
        o[1] = static_cast<float>(lab(1));
        o[2] = static_cast<float>(lab(2));
      }
    }
  }
  if (progress) progress->Update("hand inversion", 1.0);
  return out;
}

int64_t CorrectFilledGapsWithEdgeMisfits(const HandModel& model, const MarkerArray& input, InversionResult* result,
                                         int64_t fade_frames) {
  const int nf = static_cast<int>(model.forearm.reference.cols());
  const int nh = model.layout.num_shape_markers();
  MarkerArray& rec = result->reconstructed;
  if (model.fill.empty() || model.fill.markers() != nh) {
    throw InvalidInput("filled-gap correction: the hand model has no gap filler for its " + std::to_string(nh) +
                       " hand markers");
  }
  if (input.markers() != nf + nh || rec.markers() != nf + nh || rec.frames() != input.frames() ||
      result->pose.rows() != input.frames()) {
    throw InvalidInput("filled-gap correction: input is " + std::to_string(input.frames()) + "×" +
                       std::to_string(input.markers()) + " markers, the reconstruction " +
                       std::to_string(rec.frames()) + "×" + std::to_string(rec.markers()) + ", the model has " +
                       std::to_string(nf + nh));
  }
  const int64_t frames = input.frames();
  constexpr int kEdgeFrames = 4;
  // Per frame: pose, hand markers in the forearm frame (seen: observed;
  // missing: as filled, NaN when not), the pattern of seen hand markers.
  std::vector<RigidTransform> pose(static_cast<size_t>(frames));
  std::vector<uint8_t> solved(static_cast<size_t>(frames), 0);
  std::vector<Eigen::Matrix3Xd> local(static_cast<size_t>(frames));
  std::vector<std::vector<uint8_t>> seen(static_cast<size_t>(frames), std::vector<uint8_t>(static_cast<size_t>(nh), 0));
  for (int64_t f = 0; f < frames; ++f) {
    const Eigen::Matrix<double, 6, 1> pr = result->pose.row(f).transpose();
    if (!pr.allFinite()) continue;
    solved[static_cast<size_t>(f)] = 1;
    pose[static_cast<size_t>(f)] = RigidTransform::FromParameters(pr);
    const RigidTransform& x = pose[static_cast<size_t>(f)];
    Eigen::Matrix3Xd& l = local[static_cast<size_t>(f)];
    l.resize(3, nh);
    for (int j = 0; j < nh; ++j) {
      const bool v = input.Visible(f, nf + j);
      seen[static_cast<size_t>(f)][static_cast<size_t>(j)] = v ? 1 : 0;
      const float* q = v ? input.at(f, nf + j) : rec.at(f, nf + j);
      l.col(j) = IsMissing(q[0])
                     ? Eigen::Vector3d::Constant(kNaN)
                     : Eigen::Vector3d(x.rotation.transpose() * (Eigen::Vector3d(q[0], q[1], q[2]) - x.translation));
    }
  }
  // Each missing sample's gap [a, b) of its marker.
  Eigen::Matrix<int64_t, Eigen::Dynamic, Eigen::Dynamic> gap_a(frames, nh), gap_b(frames, nh);
  for (int j = 0; j < nh; ++j) {
    int64_t f = 0;
    while (f < frames) {
      if (input.Visible(f, nf + j)) {
        ++f;
        continue;
      }
      const int64_t a = f;
      while (f < frames && !input.Visible(f, nf + j)) ++f;
      for (int64_t g = a; g < f; ++g) {
        gap_a(g, j) = a;
        gap_b(g, j) = f;
      }
    }
  }
  GaussianFiller filler(model.fill);
  int64_t corrected = 0;
  for (int64_t g = 0; g < frames; ++g) {
    if (!solved[static_cast<size_t>(g)]) continue;
    const std::vector<uint8_t>& pattern = seen[static_cast<size_t>(g)];
    int nseen = 0;
    for (uint8_t v : pattern) nseen += v;
    if (nseen == 0 || nseen == nh) continue;
    // Whether frame e can be predicted with g's pattern: solved and every
    // marker seen at g known at e.
    auto usable = [&](int64_t e) {
      if (e < 0 || e >= frames || !solved[static_cast<size_t>(e)]) return false;
      const Eigen::Matrix3Xd& l = local[static_cast<size_t>(e)];
      for (int j = 0; j < nh; ++j)
        if (pattern[static_cast<size_t>(j)] && !l.col(j).allFinite()) return false;
      return true;
    };
    for (int j = 0; j < nh; ++j) {
      if (pattern[static_cast<size_t>(j)] || !local[static_cast<size_t>(g)].col(j).allFinite()) continue;
      // Mean misfit over up to kEdgeFrames frames from e outwards where j is seen.
      auto misfit = [&](int64_t e, int step, Eigen::Vector3d* out) {
        out->setZero();
        int n = 0;
        for (int k = 0; k < kEdgeFrames && e >= 0 && e < frames && input.Visible(e, nf + j); ++k, e += step) {
          if (!usable(e)) continue;
          const Eigen::Matrix3Xd& l = local[static_cast<size_t>(e)];
          *out += l.col(j) - filler.Predict(pattern, j, l);
          ++n;
        }
        if (n == 0) return false;
        *out /= n;
        return true;
      };
      const int64_t a = gap_a(g, j), b = gap_b(g, j);
      Eigen::Vector3d left, right;
      const bool has_left = misfit(a - 1, -1, &left), has_right = misfit(b, +1, &right);
      if (!has_left && !has_right) continue;
      Eigen::Vector3d add;
      if (has_left && has_right) {
        const double t = static_cast<double>(g - a + 1) / static_cast<double>(b - a + 1);
        add = (1 - t) * left + t * right;
      } else {
        const int64_t distance = has_left ? g - a + 1 : b - g;
        const double w = fade_frames > 0
                             ? std::max(0.0, 1.0 - static_cast<double>(distance) / static_cast<double>(fade_frames))
                             : 1.0;
        add = w * (has_left ? left : right);
      }
      if (!add.allFinite()) continue;
      const RigidTransform& x = pose[static_cast<size_t>(g)];
      const Eigen::Vector3d lab = x.rotation * (local[static_cast<size_t>(g)].col(j) + add) + x.translation;
      float* o = rec.at(g, nf + j);
      for (int k = 0; k < 3; ++k) o[k] = static_cast<float>(lab(k));
      ++corrected;
    }
  }
  return corrected;
}

}  // namespace csw
