// The classes armfleet's compiled fleet path binds (cpp/module.cpp), declared without
// Pinocchio's or Ruckig's headers: each is defined in a translation unit of its own
// (cpp/fleet_kernel.cpp with Pinocchio, cpp/reference_stepper.cpp with Ruckig), so the
// build compiles them in parallel and the binding does not parse either library.

#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace armfleet {

namespace nb = nanobind;

using Block = nb::ndarray<double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using Flags = nb::ndarray<bool, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Indices = nb::ndarray<const std::int64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Placements = nb::ndarray<const double, nb::shape<-1, 4, 4>, nb::c_contig, nb::device::cpu>;
using Inertias = nb::ndarray<const double, nb::shape<-1, 13>, nb::c_contig, nb::device::cpu>;
using Vector = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Array = nb::ndarray<double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

// The position controllers' law of the fleet-path arms (cpp/fleet_kernel.cpp).
class FleetKernel {
 public:
  explicit FleetKernel(const std::vector<std::int64_t>& rows);
  ~FleetKernel();
  FleetKernel(const FleetKernel&) = delete;
  FleetKernel& operator=(const FleetKernel&) = delete;

  std::size_t add_arm(const std::vector<int>& parents, const std::vector<std::string>& kinds,
                      const std::vector<std::array<double, 3>>& axes, Placements placements,
                      Inertias inertias, const std::array<double, 3>& gravity, Vector armature,
                      std::int64_t start);
  std::size_t arm_count() const;
  Eigen::VectorXd rnea(std::size_t index, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                       const Eigen::VectorXd& a);
  void control(Block block, Indices indices, double half_step_s, Flags saturated);

 private:
  struct State;  // Pinocchio's models and data, rows: cpp/fleet_kernel.cpp
  std::unique_ptr<State> state_;
};

// One jerk-limited reference stepped by Ruckig's C++ library (cpp/reference_stepper.cpp).
class ReferenceStepper {
 public:
  ReferenceStepper(std::size_t dofs, double period_s);
  ~ReferenceStepper();
  ReferenceStepper(const ReferenceStepper&) = delete;
  ReferenceStepper& operator=(const ReferenceStepper&) = delete;

  void bind(Array position, Array velocity, Array acceleration);
  void follow(const std::vector<double>& current_position, const std::vector<double>& current_velocity,
              const std::vector<double>& current_acceleration, const std::vector<double>& target_position,
              const std::vector<double>& target_velocity, const std::vector<double>& target_acceleration,
              const std::vector<double>& max_velocity, const std::vector<double>& max_acceleration,
              const std::vector<double>& max_jerk, bool velocity_interface,
              std::optional<double> minimum_duration);
  int step();

 private:
  struct State;  // Ruckig's generator, input and output: cpp/reference_stepper.cpp
  std::unique_ptr<State> state_;
  std::size_t dofs_;
  Array position_, velocity_, acceleration_;
};

}  // namespace armfleet
