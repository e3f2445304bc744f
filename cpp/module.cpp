// The Python module armfleet.controllers._fleet_kernel: nanobind's binding of the classes
// declared in cpp/fleet_kernel.hpp. Neither Pinocchio nor Ruckig is parsed here.

#include "fleet_kernel.hpp"

#include <nanobind/eigen/dense.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

namespace nb = nanobind;
using armfleet::FleetKernel;
using armfleet::ReferenceStepper;

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
