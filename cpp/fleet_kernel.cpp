// The position controllers of a world's fleet-path arms, one call per physics step.
//
// For every arm given, on its columns of the world's joint memory (a C-contiguous block,
// one row per quantity, one column per joint: armfleet/joint_memory.py), it does what
// armfleet/controllers/fleet_update.py does in numpy and Pinocchio's Python bindings:
//
//   acceleration = (q_ref - q) kp + ((v_ref - (h/2) a_ref) - v) kd + a_ref
//   torque       = RNEA(q, v, acceleration)
//   effort       = clip(torque + damping v, -limit, limit)   (saturated: |.| > limit)
//
// with the same floating-point operations in the same order (no fused multiply-adds:
// built with -ffp-contract=off), so the two paths agree to rounding of RNEA's inner
// products at most (tests/test_compiled_fleet.py). Each arm's Pinocchio model is rebuilt
// here, joint by joint, from the numbers of the Python model (placements, inertias,
// axes, gravity, armature): no URDF is parsed twice.
//
// Compile time: this file is built with PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION (CMake's
// pinocchio::pinocchio_default target), so ModelTpl<double>, DataTpl<double>(model),
// addJoint and rnea are the instantiations compiled into libpinocchio_default.so (the one
// Pinocchio's Python bindings call), not instantiated again here. Models and data are held
// by pointer and never copied or moved, so their copy and move members are not
// instantiated either. That took the compile of this file from ~65 s and 2.4 GB to ~10 s and
// 0.85 GB (g++ 12, -O3, 2-core machine); what is left is mostly parsing Pinocchio's headers.

#include "fleet_kernel.hpp"

#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>

#include <cmath>
#include <stdexcept>

namespace armfleet {

namespace {

// The rows of the joint memory the kernel reads and writes (armfleet.joint_memory.Row).
struct Rows {
  std::int64_t position, velocity, effort_command, reference_position, reference_velocity,
      reference_acceleration, kp, kd, damping, effort_limit, negative_effort_limit,
      acceleration, torque;
};

struct Arm {
  pinocchio::Model model;
  std::unique_ptr<pinocchio::Data> data;
  std::int64_t start = 0;  // first column in the memory
  std::int64_t size = 0;   // number of columns (the model's nv)
};

pinocchio::JointModel joint_model(const std::string& kind, const std::array<double, 3>& axis) {
  const Eigen::Vector3d direction(axis[0], axis[1], axis[2]);
  if (kind == "JointModelRX") return pinocchio::JointModelRX();
  if (kind == "JointModelRY") return pinocchio::JointModelRY();
  if (kind == "JointModelRZ") return pinocchio::JointModelRZ();
  if (kind == "JointModelRevoluteUnaligned") return pinocchio::JointModelRevoluteUnaligned(direction);
  if (kind == "JointModelPX") return pinocchio::JointModelPX();
  if (kind == "JointModelPY") return pinocchio::JointModelPY();
  if (kind == "JointModelPZ") return pinocchio::JointModelPZ();
  if (kind == "JointModelPrismaticUnaligned") return pinocchio::JointModelPrismaticUnaligned(direction);
  throw std::invalid_argument("the fleet kernel has no joint of kind " + kind);
}

// numpy's minimum and maximum: a NaN operand gives NaN.
inline double minimum(double a, double b) { return std::isnan(a) ? a : (a < b ? a : b); }
inline double maximum(double a, double b) { return std::isnan(a) ? a : (a > b ? a : b); }

}  // namespace

struct FleetKernel::State {
  Rows rows{};
  std::vector<std::unique_ptr<Arm>> arms;
};

FleetKernel::FleetKernel(const std::vector<std::int64_t>& rows) : state_(std::make_unique<State>()) {
  if (rows.size() != 13) throw std::invalid_argument("the fleet kernel needs 13 row indices");
  state_->rows = Rows{rows[0], rows[1], rows[2], rows[3], rows[4],  rows[5], rows[6],
                      rows[7], rows[8], rows[9], rows[10], rows[11], rows[12]};
}

FleetKernel::~FleetKernel() = default;

// Add an arm whose model has the given joints (joint 0, the universe, left out) and whose
// columns start at ``start``; return its index. Inertia rows: mass, lever (3), then the
// rotational inertia about the centre of mass, row by row (9).
std::size_t FleetKernel::add_arm(const std::vector<int>& parents, const std::vector<std::string>& kinds,
                                 const std::vector<std::array<double, 3>>& axes, Placements placements,
                                 Inertias inertias, const std::array<double, 3>& gravity,
                                 Vector armature, std::int64_t start) {
  const std::size_t joints = kinds.size();
  if (parents.size() != joints || axes.size() != joints || placements.shape(0) != joints ||
      inertias.shape(0) != joints) {
    throw std::invalid_argument("the fleet kernel needs one parent, axis, placement and inertia per joint");
  }
  auto owned = std::make_unique<Arm>();
  Arm& arm = *owned;
  for (std::size_t i = 0; i < joints; ++i) {
    Eigen::Matrix4d homogeneous;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) homogeneous(r, c) = placements(i, r, c);
    const pinocchio::SE3 placement(homogeneous);
    const auto id = arm.model.addJoint(static_cast<pinocchio::JointIndex>(parents[i]),
                                       joint_model(kinds[i], axes[i]), placement,
                                       "joint" + std::to_string(i + 1));
    Eigen::Matrix3d rotational;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) rotational(r, c) = inertias(i, 4 + 3 * r + c);
    const Eigen::Vector3d lever(inertias(i, 1), inertias(i, 2), inertias(i, 3));
    arm.model.inertias[id] = pinocchio::Inertia(inertias(i, 0), lever, rotational);
  }
  if (static_cast<std::size_t>(armature.shape(0)) != static_cast<std::size_t>(arm.model.nv)) {
    throw std::invalid_argument("the fleet kernel needs one armature value per velocity");
  }
  arm.model.gravity.linear(Eigen::Vector3d(gravity[0], gravity[1], gravity[2]));
  for (int i = 0; i < arm.model.nv; ++i) arm.model.armature[i] = armature(i);
  arm.data = std::make_unique<pinocchio::Data>(arm.model);
  arm.start = start;
  arm.size = arm.model.nv;
  state_->arms.push_back(std::move(owned));
  return state_->arms.size() - 1;
}

std::size_t FleetKernel::arm_count() const { return state_->arms.size(); }

// RNEA of arm ``index`` alone (for tests against Pinocchio's Python bindings).
Eigen::VectorXd FleetKernel::rnea(std::size_t index, const Eigen::VectorXd& q,
                                  const Eigen::VectorXd& v, const Eigen::VectorXd& a) {
  Arm& arm = *state_->arms.at(index);
  return pinocchio::rnea(arm.model, *arm.data, q, v, a);
}

// The control law of the arms ``indices`` on ``block``; ``saturated`` (one flag per column)
// is set for their clipped joints. Other columns are left alone.
void FleetKernel::control(Block block, Indices indices, double half_step_s, Flags saturated) {
  const Rows& rows = state_->rows;
  const std::int64_t columns = static_cast<std::int64_t>(block.shape(1));
  if (static_cast<std::int64_t>(saturated.shape(0)) != columns) {
    throw std::invalid_argument("saturated needs one flag per column of the block");
  }
  double* base = block.data();
  auto row = [&](std::int64_t r) { return base + r * columns; };
  const double* q = row(rows.position);
  const double* v = row(rows.velocity);
  const double* q_ref = row(rows.reference_position);
  const double* v_ref = row(rows.reference_velocity);
  const double* a_ref = row(rows.reference_acceleration);
  const double* kp = row(rows.kp);
  const double* kd = row(rows.kd);
  const double* damping = row(rows.damping);
  const double* limit = row(rows.effort_limit);
  const double* negative_limit = row(rows.negative_effort_limit);
  double* acceleration = row(rows.acceleration);
  double* torque = row(rows.torque);
  double* effort = row(rows.effort_command);
  bool* flags = saturated.data();
  for (std::size_t k = 0; k < indices.shape(0); ++k) {
    Arm& arm = *state_->arms.at(static_cast<std::size_t>(indices(k)));
    const std::int64_t start = arm.start, stop = arm.start + arm.size;
    if (stop > columns) throw std::out_of_range("an arm's columns lie outside the block");
    for (std::int64_t c = start; c < stop; ++c) {
      double feedback = q_ref[c] - q[c];
      feedback = feedback * kp[c];
      double lagging = a_ref[c] * half_step_s;
      lagging = v_ref[c] - lagging;
      lagging = lagging - v[c];
      lagging = lagging * kd[c];
      feedback = feedback + lagging;
      acceleration[c] = feedback + a_ref[c];
    }
    const Eigen::Map<const Eigen::VectorXd> q_arm(q + start, arm.size);
    const Eigen::Map<const Eigen::VectorXd> v_arm(v + start, arm.size);
    const Eigen::Map<const Eigen::VectorXd> a_arm(acceleration + start, arm.size);
    pinocchio::rnea(arm.model, *arm.data, q_arm, v_arm, a_arm);
    for (std::int64_t c = start; c < stop; ++c) {
      const double total = arm.data->tau[c - start] + damping[c] * v[c];
      torque[c] = total;
      flags[c] = std::fabs(total) > limit[c];
      effort[c] = maximum(minimum(total, limit[c]), negative_limit[c]);
    }
  }
}

}  // namespace armfleet
