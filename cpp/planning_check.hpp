// The planner's collision check and its proof of clearance, compiled (cpp/planning_check.cpp).
//
// Declared without coal's or Eigen's geometry types, so that cpp/module.cpp parses neither:
// the scene lives behind a pointer to an implementation.

#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace armfleet {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// One planning scene's kinematic tree and collision geometry, and the pairs one request
// counts: answers "is this state clear" and "is this whole path proven clear".
class SceneCheck {
 public:
  // The tree, joint by joint (the Pinocchio model's joints 1..n, in order): parent joint
  // (0: the world), 0 revolute / 1 prismatic, unit axis in the joint frame, placement in the
  // parent joint's frame (rotation row by row, then translation: 12 numbers), index of its
  // value in the configuration, how far it moves its children from its origin (a prismatic
  // joint's largest |limit|; 0 for a revolute joint); nq the configuration's size.
  SceneCheck(const std::vector<std::int64_t>& parents, const std::vector<std::int64_t>& kinds,
             const RowMatrix& axes, const RowMatrix& placements,
             const std::vector<std::int64_t>& q_indices, const std::vector<double>& travels,
             std::int64_t nq);
  ~SceneCheck();
  SceneCheck(const SceneCheck&) = delete;
  SceneCheck& operator=(const SceneCheck&) = delete;

  // A geometry on ``joint`` (0: fixed in the world) at ``placement`` (12 numbers as above):
  // kind 0 box (half sides), 1 sphere (radius), 2 cylinder (radius, half length), 3 capsule
  // (radius, half length), 4 convex hull of ``points`` (rows). Returns its index.
  std::int64_t add_geometry(std::int64_t joint, const std::vector<double>& placement,
                            std::int64_t kind, const std::vector<double>& parameters,
                            const RowMatrix& points);
  void set_placement(std::int64_t geometry, const std::vector<double>& placement);
  // The pairs checked, each closer than its margin (or far margin) being a collision; each
  // margin holds the two shapes' physics margins (``grown``).
  void set_pairs(const std::vector<std::int64_t>& first, const std::vector<std::int64_t>& second,
                 const std::vector<double>& margins, const std::vector<double>& far_margins,
                 const std::vector<double>& grown);
  // The configuration of the joints not planned, and which of its values a state sets.
  void set_configuration(const Eigen::VectorXd& q);
  void set_planned(const std::vector<std::int64_t>& columns);
  // The proof's numbers (armfleet/planning/path_check.py): per planned joint its reach
  // bound [m]; per planned arm the index of its first joint in a state; the margins between
  // bodies and within an arm, near and far.
  void set_proof(const Eigen::VectorXd& levers, const std::vector<std::int64_t>& arm_starts,
                 double near_between, double near_within, double far_between,
                 double far_within);

  // Whether ``state`` keeps every pair's margin (``far``: its far margin).
  bool clear(const Eigen::VectorXd& state, bool far);
  // Whether ``to`` and the states that cut the straight motion from ``from`` into
  // ``segments`` equal parts keep the clearance (the middle ones first): OMPL's discrete
  // motion check, in one call.
  bool clear_motion(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                    std::int64_t segments);
  // The first (segment, state) of ``path`` (rows) not proven clear, or none: with steps
  // sized by the distances found (``adaptive``), or path_check.py's walk, step for step.
  // With a ``deviation`` (per planned joint, adaptive only; one row, or one per chord): of a
  // curve through the rows that stays that close to the chord between two rows, joint by
  // joint.
  std::optional<std::pair<std::int64_t, Eigen::VectorXd>> first_failure(
      const RowMatrix& path, bool adaptive, const RowMatrix& deviation);
  // Pairs settled by the bounding volumes, and by coal, since the count was reset.
  std::int64_t checks = 0;
  std::int64_t pairs_by_volume = 0;
  std::int64_t pairs_by_coal = 0;

 private:
  std::optional<std::pair<std::int64_t, Eigen::VectorXd>> first_failure_adaptive(
      const RowMatrix& path, const RowMatrix& deviation);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace armfleet
