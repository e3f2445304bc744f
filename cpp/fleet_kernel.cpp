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

#include <nanobind/nanobind.h>
#include <nanobind/eigen/dense.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/model.hpp>
#include <ruckig/ruckig.hpp>

#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace nb = nanobind;

namespace {

using Block = nb::ndarray<double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using Flags = nb::ndarray<bool, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Indices = nb::ndarray<const std::int64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Placements = nb::ndarray<const double, nb::shape<-1, 4, 4>, nb::c_contig, nb::device::cpu>;
using Inertias = nb::ndarray<const double, nb::shape<-1, 13>, nb::c_contig, nb::device::cpu>;
using Vector = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

// The rows of the joint memory the kernel reads and writes (armfleet.joint_memory.Row).
struct Rows {
  std::int64_t position, velocity, effort_command, reference_position, reference_velocity,
      reference_acceleration, kp, kd, damping, effort_limit, negative_effort_limit,
      acceleration, torque;
};

struct Arm {
  pinocchio::Model model;
  pinocchio::Data data;
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

class FleetKernel {
 public:
  explicit FleetKernel(const std::vector<std::int64_t>& rows) {
    if (rows.size() != 13) throw std::invalid_argument("the fleet kernel needs 13 row indices");
    rows_ = Rows{rows[0], rows[1], rows[2], rows[3], rows[4],  rows[5], rows[6],
                 rows[7], rows[8], rows[9], rows[10], rows[11], rows[12]};
  }

  // Add an arm whose model has the given joints (joint 0, the universe, left out) and whose
  // columns start at ``start``; return its index. Inertia rows: mass, lever (3), then the
  // rotational inertia about the centre of mass, row by row (9).
  std::size_t add_arm(const std::vector<int>& parents, const std::vector<std::string>& kinds,
                      const std::vector<std::array<double, 3>>& axes, Placements placements,
                      Inertias inertias, const std::array<double, 3>& gravity, Vector armature,
                      std::int64_t start) {
    const std::size_t joints = kinds.size();
    if (parents.size() != joints || axes.size() != joints || placements.shape(0) != joints ||
        inertias.shape(0) != joints) {
      throw std::invalid_argument("the fleet kernel needs one parent, axis, placement and inertia per joint");
    }
    Arm arm;
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
    arm.data = pinocchio::Data(arm.model);
    arm.start = start;
    arm.size = arm.model.nv;
    arms_.push_back(std::move(arm));
    return arms_.size() - 1;
  }

  std::size_t arm_count() const { return arms_.size(); }

  // RNEA of arm ``index`` alone (for tests against Pinocchio's Python bindings).
  Eigen::VectorXd rnea(std::size_t index, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                       const Eigen::VectorXd& a) {
    Arm& arm = arms_.at(index);
    return pinocchio::rnea(arm.model, arm.data, q, v, a);
  }

  // The control law of the arms ``indices`` on ``block``; ``saturated`` (one flag per column)
  // is set for their clipped joints. Other columns are left alone.
  void control(Block block, Indices indices, double half_step_s, Flags saturated) {
    const std::int64_t columns = static_cast<std::int64_t>(block.shape(1));
    if (static_cast<std::int64_t>(saturated.shape(0)) != columns) {
      throw std::invalid_argument("saturated needs one flag per column of the block");
    }
    double* base = block.data();
    auto row = [&](std::int64_t r) { return base + r * columns; };
    const double* q = row(rows_.position);
    const double* v = row(rows_.velocity);
    const double* q_ref = row(rows_.reference_position);
    const double* v_ref = row(rows_.reference_velocity);
    const double* a_ref = row(rows_.reference_acceleration);
    const double* kp = row(rows_.kp);
    const double* kd = row(rows_.kd);
    const double* damping = row(rows_.damping);
    const double* limit = row(rows_.effort_limit);
    const double* negative_limit = row(rows_.negative_effort_limit);
    double* acceleration = row(rows_.acceleration);
    double* torque = row(rows_.torque);
    double* effort = row(rows_.effort_command);
    bool* flags = saturated.data();
    for (std::size_t k = 0; k < indices.shape(0); ++k) {
      Arm& arm = arms_.at(static_cast<std::size_t>(indices(k)));
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
      pinocchio::rnea(arm.model, arm.data, q_arm, v_arm, a_arm);
      for (std::int64_t c = start; c < stop; ++c) {
        const double total = arm.data.tau[c - start] + damping[c] * v[c];
        torque[c] = total;
        flags[c] = std::fabs(total) > limit[c];
        effort[c] = maximum(minimum(total, limit[c]), negative_limit[c]);
      }
    }
  }

 private:
  Rows rows_{};
  std::vector<Arm> arms_;
};

using Array = nb::ndarray<double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

// One jerk-limited reference stepped by Ruckig's C++ library: what JerkLimitedTrajectory.advance
// does with the Python bindings (update, copy the new state out, pass it to the input), without
// building three Python lists per step. It writes into three bound arrays (views of the joint
// memory, or the trajectory's own arrays).
class ReferenceStepper {
 public:
  ReferenceStepper(std::size_t dofs, double period_s)
      : otg_(dofs, period_s), input_(dofs), output_(dofs), dofs_(dofs) {}

  void bind(Array position, Array velocity, Array acceleration) {
    if (position.shape(0) != dofs_ || velocity.shape(0) != dofs_ || acceleration.shape(0) != dofs_) {
      throw std::invalid_argument("a reference stepper binds three arrays of one value per joint");
    }
    position_ = position;
    velocity_ = velocity;
    acceleration_ = acceleration;
  }

  // The motion to follow from now on: Ruckig's input, field by field (the rest default).
  void follow(const std::vector<double>& current_position, const std::vector<double>& current_velocity,
              const std::vector<double>& current_acceleration, const std::vector<double>& target_position,
              const std::vector<double>& target_velocity, const std::vector<double>& target_acceleration,
              const std::vector<double>& max_velocity, const std::vector<double>& max_acceleration,
              const std::vector<double>& max_jerk, bool velocity_interface,
              std::optional<double> minimum_duration) {
    ruckig::InputParameter<ruckig::DynamicDOFs> input(dofs_);
    copy(current_position, input.current_position);
    copy(current_velocity, input.current_velocity);
    copy(current_acceleration, input.current_acceleration);
    copy(target_position, input.target_position);
    copy(target_velocity, input.target_velocity);
    copy(target_acceleration, input.target_acceleration);
    copy(max_velocity, input.max_velocity);
    copy(max_acceleration, input.max_acceleration);
    copy(max_jerk, input.max_jerk);
    input.control_interface =
        velocity_interface ? ruckig::ControlInterface::Velocity : ruckig::ControlInterface::Position;
    input.minimum_duration = minimum_duration;
    input_ = input;
  }

  // One period along the motion; Ruckig's result (Working 0, Finished 1, errors < 0).
  int step() {
    const ruckig::Result result = otg_.update(input_, output_);
    if (result != ruckig::Result::Working && result != ruckig::Result::Finished) {
      return static_cast<int>(result);
    }
    double* position = position_.data();
    double* velocity = velocity_.data();
    double* acceleration = acceleration_.data();
    if (position == nullptr) throw std::logic_error("a reference stepper steps into bound arrays");
    for (std::size_t i = 0; i < dofs_; ++i) {
      position[i] = output_.new_position[i];
      velocity[i] = output_.new_velocity[i];
      acceleration[i] = output_.new_acceleration[i];
    }
    output_.pass_to_input(input_);
    return static_cast<int>(result);
  }

 private:
  void copy(const std::vector<double>& from, std::vector<double>& to) const {
    if (from.size() != dofs_) throw std::invalid_argument("a Ruckig input has one value per joint");
    to = from;
  }

  ruckig::Ruckig<ruckig::DynamicDOFs> otg_;
  ruckig::InputParameter<ruckig::DynamicDOFs> input_;
  ruckig::OutputParameter<ruckig::DynamicDOFs> output_;
  std::size_t dofs_;
  Array position_, velocity_, acceleration_;
};

}  // namespace

NB_MODULE(_fleet_kernel, module) {
  module.doc() = "armfleet's compiled fleet path: the position controllers' law, RNEA included.";
  nb::class_<FleetKernel>(module, "FleetKernel")
      .def(nb::init<const std::vector<std::int64_t>&>(), nb::arg("rows"))
      .def("add_arm", &FleetKernel::add_arm, nb::arg("parents"), nb::arg("kinds"),
           nb::arg("axes"), nb::arg("placements"), nb::arg("inertias"), nb::arg("gravity"),
           nb::arg("armature"), nb::arg("start"))
      .def("arm_count", &FleetKernel::arm_count)
      .def("rnea", &FleetKernel::rnea, nb::arg("index"), nb::arg("q"), nb::arg("v"),
           nb::arg("a"))
      .def("control", &FleetKernel::control, nb::arg("block"), nb::arg("indices"),
           nb::arg("half_step_s"), nb::arg("saturated"));
  nb::class_<ReferenceStepper>(module, "ReferenceStepper")
      .def(nb::init<std::size_t, double>(), nb::arg("dofs"), nb::arg("period_s"))
      .def("bind", &ReferenceStepper::bind, nb::arg("position"), nb::arg("velocity"),
           nb::arg("acceleration"))
      .def("follow", &ReferenceStepper::follow, nb::arg("current_position"),
           nb::arg("current_velocity"), nb::arg("current_acceleration"), nb::arg("target_position"),
           nb::arg("target_velocity"), nb::arg("target_acceleration"), nb::arg("max_velocity"),
           nb::arg("max_acceleration"), nb::arg("max_jerk"), nb::arg("velocity_interface"),
           nb::arg("minimum_duration").none())
      .def("step", &ReferenceStepper::step);
}
