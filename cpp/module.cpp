// The Python module armfleet.controllers._fleet_kernel: nanobind's binding of the classes
// declared in cpp/fleet_kernel.hpp and cpp/planning_check.hpp. Neither Pinocchio, Ruckig
// nor coal is parsed here.

#include "fleet_kernel.hpp"
#include "planning_check.hpp"

#include <nanobind/eigen/dense.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

namespace nb = nanobind;
using armfleet::FleetKernel;
using armfleet::ReferenceStepper;
using armfleet::SceneCheck;

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
  // The planner's checks release the GIL: a search in one thread leaves the others running.
  using release = nb::call_guard<nb::gil_scoped_release>;
  nb::class_<SceneCheck>(module, "SceneCheck")
      .def(nb::init<const std::vector<std::int64_t>&, const std::vector<std::int64_t>&,
                    const armfleet::RowMatrix&, const armfleet::RowMatrix&,
                    const std::vector<std::int64_t>&, const std::vector<double>&, std::int64_t>(),
           nb::arg("parents"), nb::arg("kinds"), nb::arg("axes"), nb::arg("placements"),
           nb::arg("q_indices"), nb::arg("travels"), nb::arg("nq"))
      .def("add_geometry", &SceneCheck::add_geometry, nb::arg("joint"), nb::arg("placement"),
           nb::arg("kind"), nb::arg("parameters"), nb::arg("points"))
      .def("set_placement", &SceneCheck::set_placement, nb::arg("geometry"),
           nb::arg("placement"))
      .def("set_pairs", &SceneCheck::set_pairs, nb::arg("first"), nb::arg("second"),
           nb::arg("margins"), nb::arg("far_margins"), nb::arg("grown"))
      .def("set_configuration", &SceneCheck::set_configuration, nb::arg("q"))
      .def("set_planned", &SceneCheck::set_planned, nb::arg("columns"))
      .def("set_proof", &SceneCheck::set_proof, nb::arg("levers"), nb::arg("arm_starts"),
           nb::arg("near_between"), nb::arg("near_within"), nb::arg("far_between"),
           nb::arg("far_within"))
      .def("clear", &SceneCheck::clear, nb::arg("state"), nb::arg("far") = false, release())
      .def("clear_motion", &SceneCheck::clear_motion, nb::arg("start"), nb::arg("end"),
           nb::arg("segments"), release())
      .def("first_failure", &SceneCheck::first_failure, nb::arg("path"),
           nb::arg("adaptive") = true, nb::arg("deviation") = armfleet::RowMatrix(), release())
      .def_rw("checks", &SceneCheck::checks)
      .def_rw("pairs_by_volume", &SceneCheck::pairs_by_volume)
      .def_rw("pairs_by_coal", &SceneCheck::pairs_by_coal);
}
