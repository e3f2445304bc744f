// One jerk-limited reference stepped by Ruckig's C++ library: what JerkLimitedTrajectory.advance
// does with the Python bindings (update, copy the new state out, pass it to the input), without
// building three Python lists per step. It writes into three bound arrays (views of the joint
// memory, or the trajectory's own arrays). A translation unit of its own: Ruckig's templates
// compile here, beside cpp/fleet_kernel.cpp's Pinocchio (the build runs both at once).

#include "fleet_kernel.hpp"

#include <ruckig/ruckig.hpp>

#include <stdexcept>

namespace armfleet {

struct ReferenceStepper::State {
  State(std::size_t dofs, double period_s) : otg(dofs, period_s), input(dofs), output(dofs) {}
  ruckig::Ruckig<ruckig::DynamicDOFs> otg;
  ruckig::InputParameter<ruckig::DynamicDOFs> input;
  ruckig::OutputParameter<ruckig::DynamicDOFs> output;
};

ReferenceStepper::ReferenceStepper(std::size_t dofs, double period_s)
    : state_(std::make_unique<State>(dofs, period_s)), dofs_(dofs) {}

ReferenceStepper::~ReferenceStepper() = default;

void ReferenceStepper::bind(Array position, Array velocity, Array acceleration) {
  if (position.shape(0) != dofs_ || velocity.shape(0) != dofs_ || acceleration.shape(0) != dofs_) {
    throw std::invalid_argument("a reference stepper binds three arrays of one value per joint");
  }
  position_ = position;
  velocity_ = velocity;
  acceleration_ = acceleration;
}

namespace {
void copy(const std::vector<double>& from, std::vector<double>& to, std::size_t dofs) {
  if (from.size() != dofs) throw std::invalid_argument("a Ruckig input has one value per joint");
  to = from;
}
}  // namespace

// The motion to follow from now on: Ruckig's input, field by field (the rest default).
void ReferenceStepper::follow(const std::vector<double>& current_position,
                              const std::vector<double>& current_velocity,
                              const std::vector<double>& current_acceleration,
                              const std::vector<double>& target_position,
                              const std::vector<double>& target_velocity,
                              const std::vector<double>& target_acceleration,
                              const std::vector<double>& max_velocity,
                              const std::vector<double>& max_acceleration,
                              const std::vector<double>& max_jerk, bool velocity_interface,
                              std::optional<double> minimum_duration) {
  ruckig::InputParameter<ruckig::DynamicDOFs> input(dofs_);
  copy(current_position, input.current_position, dofs_);
  copy(current_velocity, input.current_velocity, dofs_);
  copy(current_acceleration, input.current_acceleration, dofs_);
  copy(target_position, input.target_position, dofs_);
  copy(target_velocity, input.target_velocity, dofs_);
  copy(target_acceleration, input.target_acceleration, dofs_);
  copy(max_velocity, input.max_velocity, dofs_);
  copy(max_acceleration, input.max_acceleration, dofs_);
  copy(max_jerk, input.max_jerk, dofs_);
  input.control_interface =
      velocity_interface ? ruckig::ControlInterface::Velocity : ruckig::ControlInterface::Position;
  input.minimum_duration = minimum_duration;
  state_->input = input;
}

// One period along the motion; Ruckig's result (Working 0, Finished 1, errors < 0).
int ReferenceStepper::step() {
  State& s = *state_;
  const ruckig::Result result = s.otg.update(s.input, s.output);
  if (result != ruckig::Result::Working && result != ruckig::Result::Finished) {
    return static_cast<int>(result);
  }
  double* position = position_.data();
  double* velocity = velocity_.data();
  double* acceleration = acceleration_.data();
  if (position == nullptr) throw std::logic_error("a reference stepper steps into bound arrays");
  for (std::size_t i = 0; i < dofs_; ++i) {
    position[i] = s.output.new_position[i];
    velocity[i] = s.output.new_velocity[i];
    acceleration[i] = s.output.new_acceleration[i];
  }
  s.output.pass_to_input(s.input);
  return static_cast<int>(result);
}

}  // namespace armfleet
