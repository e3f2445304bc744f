// The planner's collision check and its proof of clearance (armfleet/planning/scene.py,
// armfleet/planning/path_check.py), one call per state and one per path.
//
// The scene is rebuilt here from the numbers of the Python scene: each joint's parent,
// axis and placement (forward kinematics is a product of placements and rotations about
// an axis), each geometry's coal shape (a convex hull again from its hull's points, boxes,
// spheres, cylinders, capsules as they are). A pair is asked of coal exactly as Pinocchio
// asks it (a CollisionRequest with the pair's margin as ``security_margin``), so the answer
// is the Python check's; but first each geometry's bounding volume, which CONTAINS it (a
// sphere around a hull's points; a box is its own), settles the pairs that are far apart
// without coal: when the volumes are further apart than the margin (plus coal's own
// 1e-6 of slack), so are the shapes inside them.
//
// Nothing of Pinocchio is parsed here (only coal and Eigen): its own translation unit, so
// the build compiles it beside the fleet kernel's.

#include "planning_check.hpp"

#include <coal/collision.h>
#include <coal/distance.h>
#include <coal/shape/geometric_shapes.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace armfleet {

namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

struct Pose {
  Mat3 rotation = Mat3::Identity();
  Vec3 translation = Vec3::Zero();
  Pose operator*(const Pose& other) const {
    return {rotation * other.rotation, rotation * other.translation + translation};
  }
};

Pose pose_of(const double* numbers) {
  Pose pose;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) pose.rotation(r, c) = numbers[3 * r + c];
  pose.translation = Vec3(numbers[9], numbers[10], numbers[11]);
  return pose;
}

struct Joint {
  std::int64_t parent;
  bool prismatic;
  Vec3 axis;
  Pose placement;
  std::int64_t q_index;
  double travel;  // how far a prismatic joint moves its children from its origin [m]
};

struct Geometry {
  std::int64_t joint;
  Pose placement;             // in its joint's frame
  std::shared_ptr<coal::CollisionGeometry> shape;
  Vec3 center;                // of the sphere containing it, in its own frame
  double radius;
  bool is_box;
  Vec3 half_sides;
  // A capsule containing it (a hull's, a cylinder's, a capsule's own): the segment from
  // ``tip_a`` to ``tip_b`` in its own frame, widened by ``capsule_radius``; none when
  // ``has_capsule`` is false (a box, a sphere: their own bounds are tighter).
  bool has_capsule = false;
  Vec3 tip_a = Vec3::Zero(), tip_b = Vec3::Zero();
  double capsule_radius = 0.0;
  Pose world;                 // where it is at the state checked
  Vec3 world_center;
  Vec3 world_tip_a = Vec3::Zero(), world_tip_b = Vec3::Zero();
};

struct Pair {
  std::int64_t first, second;
  double margin, far_margin;
  double grown;  // the two shapes' physics margins, within ``margin``
  std::unique_ptr<coal::ComputeCollision> collide;
  std::unique_ptr<coal::ComputeDistance> distance;  // made on first use
  // GJK starts from where it ended for this pair the last time (states checked one after
  // the other are near each other): the same answer, in fewer iterations.
  coal::Vec3s guess{1, 0, 0};
  coal::support_func_guess_t support_guess = coal::support_func_guess_t::Zero();
};

// Distance from a point to a box (centred at ``box.world``, half sides), 0 inside.
double point_to_box(const Vec3& point, const Geometry& box) {
  const Vec3 local = box.world.rotation.transpose() * (point - box.world.translation);
  const Vec3 outside = (local.cwiseAbs() - box.half_sides).cwiseMax(0.0);
  return outside.norm();
}

// The distance between segments [p0, p1] and [q0, q1] (closest points by clamping, as in
// Ericson's Real-Time Collision Detection, 5.1.9).
double segment_to_segment(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  constexpr double tiny = 1e-18;
  double s = 0.0, t = 0.0;
  if (a <= tiny && e <= tiny) return r.norm();
  if (a <= tiny) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= tiny) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denominator = a * e - b * b;
      s = denominator > tiny ? std::clamp((b * f - c * e) / denominator, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

// A lower bound on the distance from segment [p0, p1] to a box: the distance to a convex
// set is convex along the segment, so a golden-section search brackets its minimum; the
// bracket's width times the segment's length (the function is 1-Lipschitz in arc length)
// is taken off what was found.
double segment_to_box(const Vec3& p0, const Vec3& p1, const Geometry& box) {
  const Mat3 to_box = box.world.rotation.transpose();
  const Vec3 a = to_box * (p0 - box.world.translation);
  const Vec3 d = to_box * (p1 - p0);
  auto at = [&](double t) {
    return ((a + t * d).cwiseAbs() - box.half_sides).cwiseMax(0.0).norm();
  };
  constexpr double golden = 0.6180339887498949;
  double low = 0.0, high = 1.0;
  double x1 = high - golden * (high - low), x2 = low + golden * (high - low);
  double f1 = at(x1), f2 = at(x2);
  double best = std::min({at(0.0), at(1.0), f1, f2});
  for (int k = 0; k < 24 && best > 0.0; ++k) {
    if (f1 <= f2) {
      high = x2, x2 = x1, f2 = f1;
      x1 = high - golden * (high - low);
      f1 = at(x1);
      best = std::min(best, f1);
    } else {
      low = x1, x1 = x2, f1 = f2;
      x2 = low + golden * (high - low);
      f2 = at(x2);
      best = std::min(best, f2);
    }
  }
  return best - (high - low) * d.norm();
}

// A lower bound on the distance between two geometries (from their containing volumes):
// the spheres first; where they do not settle ``needed``, the capsules and boxes.
double volume_distance(const Geometry& a, const Geometry& b, double needed) {
  double bound = (a.world_center - b.world_center).norm() - a.radius - b.radius;
  if (bound > needed) return bound;
  if (b.is_box) bound = std::max(bound, point_to_box(a.world_center, b) - a.radius);
  if (a.is_box) bound = std::max(bound, point_to_box(b.world_center, a) - b.radius);
  if (bound > needed) return bound;
  if (a.has_capsule && b.has_capsule) {
    bound = std::max(bound, segment_to_segment(a.world_tip_a, a.world_tip_b, b.world_tip_a,
                                               b.world_tip_b) -
                                a.capsule_radius - b.capsule_radius);
  } else if (a.has_capsule && b.is_box) {
    bound = std::max(bound, segment_to_box(a.world_tip_a, a.world_tip_b, b) - a.capsule_radius);
  } else if (b.has_capsule && a.is_box) {
    bound = std::max(bound, segment_to_box(b.world_tip_a, b.world_tip_b, a) - b.capsule_radius);
  } else if (a.has_capsule) {
    bound = std::max(bound, segment_to_segment(a.world_tip_a, a.world_tip_b, b.world_center,
                                               b.world_center) -
                                a.capsule_radius - b.radius);
  } else if (b.has_capsule) {
    bound = std::max(bound, segment_to_segment(b.world_tip_a, b.world_tip_b, a.world_center,
                                               a.world_center) -
                                b.capsule_radius - a.radius);
  }
  return bound;
}

// The capsule containing ``points``: its segment along their principal axis, between the
// extreme projections, its radius their largest distance from that axis (every point then
// lies within it, and so does their convex hull).
void contain_in_capsule(Geometry& geometry, const RowMatrix& points) {
  const Vec3 mean = points.colwise().mean().transpose();
  Mat3 spread = Mat3::Zero();
  for (Eigen::Index r = 0; r < points.rows(); ++r) {
    const Vec3 offset = points.row(r).transpose() - mean;
    spread += offset * offset.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Mat3> solver(spread);
  const Vec3 axis = solver.eigenvectors().col(2).normalized();
  double low = std::numeric_limits<double>::infinity(), high = -low, radius = 0.0;
  for (Eigen::Index r = 0; r < points.rows(); ++r) {
    const Vec3 offset = points.row(r).transpose() - mean;
    const double along = offset.dot(axis);
    low = std::min(low, along);
    high = std::max(high, along);
    radius = std::max(radius, (offset - along * axis).norm());
  }
  geometry.has_capsule = true;
  geometry.tip_a = mean + low * axis;
  geometry.tip_b = mean + high * axis;
  geometry.capsule_radius = radius * (1.0 + 1e-9) + 1e-12;
}

// Convex hulls already made, by their points' bytes: the checkers of every set of arms and
// every pooled scene share one coal hull per mesh (qhull and the neighbour tables cost
// milliseconds per link; a shape is only read by coal's queries).
std::shared_ptr<coal::CollisionGeometry> shared_hull(const RowMatrix& points) {
  static std::mutex lock;
  static std::map<std::string, std::weak_ptr<coal::CollisionGeometry>> hulls;
  std::string key(reinterpret_cast<const char*>(points.data()),
                  static_cast<std::size_t>(points.size()) * sizeof(double));
  const std::lock_guard<std::mutex> guard(lock);
  auto found = hulls.find(key);
  if (found != hulls.end()) {
    if (auto hull = found->second.lock()) return hull;
  }
  auto vertices = std::make_shared<std::vector<coal::Vec3s>>();
  for (Eigen::Index r = 0; r < points.rows(); ++r)
    vertices->emplace_back(points(r, 0), points(r, 1), points(r, 2));
  std::shared_ptr<coal::CollisionGeometry> hull(coal::ConvexBase::convexHull(
      vertices, static_cast<unsigned int>(vertices->size()), true, "Qt"));
  hull->computeLocalAABB();
  for (auto entry = hulls.begin(); entry != hulls.end();)  // hulls no checker holds now
    entry = entry->second.expired() ? hulls.erase(entry) : std::next(entry);
  hulls[key] = hull;
  return hull;
}

coal::Transform3s coal_pose(const Pose& pose) {
  return coal::Transform3s(pose.rotation, pose.translation);
}

}  // namespace

struct SceneCheck::Impl {
  std::vector<Joint> joints;  // joints[0] is the world
  std::vector<Pose> joint_poses;
  std::vector<Geometry> geometries;
  std::vector<Pair> pairs;
  // The spheres' test, compact: per geometry its sphere's centre where it is; per pair its
  // two geometries and the squared distance between centres beyond which the spheres
  // settle it (the radii and the margin, near and far).
  std::vector<Vec3> centers;
  std::vector<std::int32_t> pair_first, pair_second;
  std::vector<double> settled_near, settled_far;
  // The pair that last found a state not clear, asked first: states checked one after the
  // other are near each other, and a state through something is usually through the same.
  std::size_t last_hit = 0;
  Eigen::VectorXd q;
  std::vector<std::int64_t> planned;
  Eigen::VectorXd levers;
  std::vector<std::int64_t> arm_starts;
  double near_between = 0, near_within = 0, far_between = 0, far_within = 0;
  // Per pair and planned joint: how far the pair can close per unit of that joint's motion
  // (its reach to the shape it moves relative to the other); made again when stale.
  RowMatrix weights;
  bool weights_stale = true;
  coal::DistanceRequest distance_request{false, false};
  coal::CollisionRequest request = [] {
    coal::CollisionRequest made(coal::NO_REQUEST, 1);
    made.gjk_initial_guess = coal::GJKInitialGuess::CachedGuess;
    return made;
  }();
  // Joints (and geometries) a state moves; the others are placed once per configuration.
  std::vector<std::size_t> moving_joints;
  std::vector<std::size_t> moving_geometries;

  void place_joint(std::size_t j) {
    const Joint& joint = joints[j];
    const double value = q[joint.q_index];
    Pose motion;
    if (joint.prismatic) {
      motion.translation = joint.axis * value;
    } else {
      motion.rotation = Eigen::AngleAxisd(value, joint.axis).toRotationMatrix();
    }
    joint_poses[j] = joint_poses[joint.parent] * joint.placement * motion;
  }

  void place_geometry(Geometry& geometry) {
    if (geometry.joint != 0) geometry.world = joint_poses[geometry.joint] * geometry.placement;
    geometry.world_center = geometry.world.rotation * geometry.center + geometry.world.translation;
    if (geometry.has_capsule) {
      geometry.world_tip_a = geometry.world.rotation * geometry.tip_a + geometry.world.translation;
      geometry.world_tip_b = geometry.world.rotation * geometry.tip_b + geometry.world.translation;
    }
  }

  // Everything, where the configuration puts it; then which joints the planned columns move.
  void place_all() {
    std::vector<bool> moves(joints.size(), false);
    for (std::size_t j = 1; j < joints.size(); ++j) {
      place_joint(j);
      const bool planned_here =
          std::find(planned.begin(), planned.end(), joints[j].q_index) != planned.end();
      moves[j] = planned_here || moves[joints[j].parent];
    }
    moving_joints.clear();
    for (std::size_t j = 1; j < joints.size(); ++j)
      if (moves[j]) moving_joints.push_back(j);
    moving_geometries.clear();
    for (std::size_t g = 0; g < geometries.size(); ++g) {
      place_geometry(geometries[g]);
      centers[g] = geometries[g].world_center;
      if (moves[geometries[g].joint]) moving_geometries.push_back(g);
    }
  }

  void place(const Eigen::VectorXd& state) {
    for (std::size_t k = 0; k < planned.size(); ++k) q[planned[k]] = state[k];
    for (std::size_t j : moving_joints) place_joint(j);
    for (std::size_t g : moving_geometries) {
      place_geometry(geometries[g]);
      centers[g] = geometries[g].world_center;
    }
  }

  // Per geometry and planned joint, a bound on how far a point of the geometry moves per
  // unit of that joint (0 when the joint does not carry it): a revolute joint's reach, the
  // geometry's extent from its own joint plus every joint offset (and prismatic travel)
  // between; 1 for a prismatic joint.
  RowMatrix reaches() const {
    const auto count = static_cast<Eigen::Index>(planned.size());
    RowMatrix reach = RowMatrix::Zero(static_cast<Eigen::Index>(geometries.size()), count);
    std::vector<std::int64_t> planned_joint(planned.size(), -1);
    for (std::size_t k = 0; k < planned.size(); ++k)
      for (std::size_t j = 1; j < joints.size(); ++j)
        if (joints[j].q_index == planned[k]) planned_joint[k] = static_cast<std::int64_t>(j);
    for (std::size_t g = 0; g < geometries.size(); ++g) {
      const Geometry& geometry = geometries[g];
      // Its joint's origin to any point of it: the placement, then its bounding sphere.
      double lever = geometry.placement.translation.norm() + geometry.center.norm() + geometry.radius;
      // Walk from the geometry's joint to the root, adding each joint's offset after it.
      for (std::int64_t j = geometry.joint; j != 0; j = joints[j].parent) {
        for (std::size_t k = 0; k < planned.size(); ++k)
          if (planned_joint[k] == j)
            reach(static_cast<Eigen::Index>(g), static_cast<Eigen::Index>(k)) =
                joints[j].prismatic ? 1.0 : lever;
        lever += joints[j].placement.translation.norm() + joints[j].travel;
      }
    }
    return reach;
  }

  void update_weights() {
    if (!weights_stale) return;
    const RowMatrix reach = reaches();
    weights = RowMatrix::Zero(static_cast<Eigen::Index>(pairs.size()), reach.cols());
    for (std::size_t p = 0; p < pairs.size(); ++p) {
      const auto a = static_cast<Eigen::Index>(pairs[p].first);
      const auto b = static_cast<Eigen::Index>(pairs[p].second);
      for (Eigen::Index k = 0; k < reach.cols(); ++k) {
        // A joint that carries both shapes moves them together: it does not close the pair.
        const bool on_a = reach(a, k) > 0.0, on_b = reach(b, k) > 0.0;
        if (on_a != on_b) weights(static_cast<Eigen::Index>(p), k) = reach(a, k) + reach(b, k);
      }
    }
    weights_stale = false;
  }

  // coal's distance of a pair at the placed state, less its physics margins and GJK's
  // tolerance: how far the two shapes may close before PyBullet's would meet.
  double exact_slack(Pair& pair) {
    const Geometry& a = geometries[pair.first];
    const Geometry& b = geometries[pair.second];
    if (!pair.distance)
      pair.distance = std::make_unique<coal::ComputeDistance>(a.shape.get(), b.shape.get());
    coal::DistanceResult result;
    const double distance =
        (*pair.distance)(coal_pose(a.world), coal_pose(b.world), distance_request, result);
    return distance - pair.grown - 1e-5 * (1.0 + std::abs(distance));
  }
};

SceneCheck::SceneCheck(const std::vector<std::int64_t>& parents,
                       const std::vector<std::int64_t>& kinds, const RowMatrix& axes,
                       const RowMatrix& placements, const std::vector<std::int64_t>& q_indices,
                       const std::vector<double>& travels, std::int64_t nq)
    : impl_(std::make_unique<Impl>()) {
  const std::size_t count = parents.size();
  if (kinds.size() != count || q_indices.size() != count || travels.size() != count ||
      static_cast<std::size_t>(axes.rows()) != count ||
      static_cast<std::size_t>(placements.rows()) != count || axes.cols() != 3 ||
      placements.cols() != 12)
    throw std::invalid_argument("one parent, kind, axis, placement and index per joint");
  impl_->joints.push_back(Joint{0, false, Vec3::UnitZ(), Pose{}, 0, 0.0});
  for (std::size_t j = 0; j < count; ++j) {
    if (parents[j] < 0 || static_cast<std::size_t>(parents[j]) > j || q_indices[j] < 0 ||
        q_indices[j] >= nq)
      throw std::invalid_argument("a joint's parent must come before it, its index within nq");
    impl_->joints.push_back(Joint{parents[j], kinds[j] == 1, axes.row(j).transpose().normalized(),
                                  pose_of(placements.row(j).data()), q_indices[j],
                                  std::abs(travels[j])});
  }
  impl_->joint_poses.assign(impl_->joints.size(), Pose{});
  impl_->q = Eigen::VectorXd::Zero(nq);
}

SceneCheck::~SceneCheck() = default;

std::int64_t SceneCheck::add_geometry(std::int64_t joint, const std::vector<double>& placement,
                                      std::int64_t kind, const std::vector<double>& parameters,
                                      const RowMatrix& points) {
  if (joint < 0 || static_cast<std::size_t>(joint) >= impl_->joints.size() ||
      placement.size() != 12)
    throw std::invalid_argument("a geometry needs a joint of the scene and 12 numbers of placement");
  Geometry geometry;
  geometry.joint = joint;
  geometry.placement = pose_of(placement.data());
  geometry.world = geometry.placement;
  geometry.is_box = false;
  geometry.center = Vec3::Zero();
  geometry.half_sides = Vec3::Zero();
  auto needs = [&](std::size_t n) {
    if (parameters.size() != n) throw std::invalid_argument("wrong number of shape parameters");
  };
  switch (kind) {
    case 0:
      needs(3);
      geometry.half_sides = Vec3(parameters[0], parameters[1], parameters[2]);
      geometry.shape = std::make_shared<coal::Box>(2.0 * geometry.half_sides);
      geometry.radius = geometry.half_sides.norm();
      geometry.is_box = true;
      break;
    case 1:
      needs(1);
      geometry.shape = std::make_shared<coal::Sphere>(parameters[0]);
      geometry.radius = parameters[0];
      break;
    case 2:
      needs(2);
      geometry.shape = std::make_shared<coal::Cylinder>(parameters[0], 2.0 * parameters[1]);
      geometry.radius = std::hypot(parameters[0], parameters[1]);
      geometry.has_capsule = true;  // the cylinder's axis (z), widened by its radius
      geometry.tip_a = Vec3(0.0, 0.0, -parameters[1]);
      geometry.tip_b = Vec3(0.0, 0.0, parameters[1]);
      geometry.capsule_radius = parameters[0] * (1.0 + 1e-9) + 1e-12;
      break;
    case 3:
      needs(2);
      geometry.shape = std::make_shared<coal::Capsule>(parameters[0], 2.0 * parameters[1]);
      geometry.radius = parameters[0] + parameters[1];
      geometry.has_capsule = true;
      geometry.tip_a = Vec3(0.0, 0.0, -parameters[1]);
      geometry.tip_b = Vec3(0.0, 0.0, parameters[1]);
      geometry.capsule_radius = parameters[0] * (1.0 + 1e-9) + 1e-12;
      break;
    case 4: {
      if (points.cols() != 3 || points.rows() < 4)
        throw std::invalid_argument("a convex hull needs at least 4 points (rows of 3)");
      const Vec3 low = points.colwise().minCoeff().transpose();
      const Vec3 high = points.colwise().maxCoeff().transpose();
      geometry.center = (low + high) / 2.0;
      geometry.radius = 0.0;
      for (Eigen::Index r = 0; r < points.rows(); ++r)
        geometry.radius =
            std::max(geometry.radius, (points.row(r).transpose() - geometry.center).norm());
      geometry.shape = shared_hull(points);
      contain_in_capsule(geometry, points);
      break;
    }
    default:
      throw std::invalid_argument("shape kind must be 0 box, 1 sphere, 2 cylinder, 3 capsule, 4 convex");
  }
  // Rounding: the sphere grows by a part in 10^9 so that it contains every vertex.
  geometry.radius = geometry.radius * (1.0 + 1e-9) + 1e-12;
  if (kind != 4) geometry.shape->computeLocalAABB();
  impl_->geometries.push_back(std::move(geometry));
  impl_->centers.emplace_back(Vec3::Zero());
  impl_->place_all();
  return static_cast<std::int64_t>(impl_->geometries.size()) - 1;
}

void SceneCheck::set_placement(std::int64_t geometry, const std::vector<double>& placement) {
  if (geometry < 0 || static_cast<std::size_t>(geometry) >= impl_->geometries.size() ||
      placement.size() != 12)
    throw std::invalid_argument("no such geometry, or not 12 numbers of placement");
  Geometry& item = impl_->geometries[geometry];
  item.placement = pose_of(placement.data());
  if (item.joint == 0) item.world = item.placement;
  else impl_->weights_stale = true;  // a held object, elsewhere in the hand
  impl_->place_geometry(item);
  impl_->centers[static_cast<std::size_t>(geometry)] = item.world_center;
}

void SceneCheck::set_pairs(const std::vector<std::int64_t>& first,
                           const std::vector<std::int64_t>& second,
                           const std::vector<double>& margins,
                           const std::vector<double>& far_margins,
                           const std::vector<double>& grown) {
  const std::size_t count = first.size();
  if (second.size() != count || margins.size() != count || far_margins.size() != count ||
      grown.size() != count)
    throw std::invalid_argument("one first, second, margin, far margin and growth per pair");
  const auto size = static_cast<std::int64_t>(impl_->geometries.size());
  impl_->pairs.clear();
  for (std::size_t k = 0; k < count; ++k) {
    if (first[k] < 0 || first[k] >= size || second[k] < 0 || second[k] >= size)
      throw std::invalid_argument("a pair names a geometry the scene does not have");
    const auto* a = impl_->geometries[first[k]].shape.get();
    const auto* b = impl_->geometries[second[k]].shape.get();
    if (!(grown[k] >= 0.0 && margins[k] > grown[k]))
      throw std::invalid_argument("a pair's margin must exceed its shapes' physics margins");
    impl_->pairs.push_back(Pair{first[k], second[k], margins[k], far_margins[k], grown[k],
                                std::make_unique<coal::ComputeCollision>(a, b), nullptr});
  }
  impl_->pair_first.clear(), impl_->pair_second.clear();
  impl_->settled_near.clear(), impl_->settled_far.clear();
  for (const Pair& pair : impl_->pairs) {
    const double radii =
        impl_->geometries[pair.first].radius + impl_->geometries[pair.second].radius;
    impl_->pair_first.push_back(static_cast<std::int32_t>(pair.first));
    impl_->pair_second.push_back(static_cast<std::int32_t>(pair.second));
    impl_->settled_near.push_back(std::pow(radii + pair.margin + 1e-6, 2));
    impl_->settled_far.push_back(std::pow(radii + pair.far_margin + 1e-6, 2));
  }
  impl_->last_hit = 0;
  impl_->weights_stale = true;
}

void SceneCheck::set_configuration(const Eigen::VectorXd& q) {
  if (q.size() != impl_->q.size()) throw std::invalid_argument("q must have nq values");
  impl_->q = q;
  impl_->place_all();
}

void SceneCheck::set_planned(const std::vector<std::int64_t>& columns) {
  for (auto column : columns)
    if (column < 0 || column >= impl_->q.size())
      throw std::invalid_argument("a planned column outside the configuration");
  impl_->planned = columns;
  impl_->weights_stale = true;
  impl_->place_all();
}

void SceneCheck::set_proof(const Eigen::VectorXd& levers,
                           const std::vector<std::int64_t>& arm_starts, double near_between,
                           double near_within, double far_between, double far_within) {
  if (static_cast<std::size_t>(levers.size()) != impl_->planned.size() || arm_starts.empty() ||
      arm_starts[0] != 0)
    throw std::invalid_argument("one lever per planned joint; the first arm starts at 0");
  if (!(near_between > 0 && near_within > 0 && far_between > 0 && far_within > 0))
    throw std::invalid_argument("a contact-free proof needs margins > 0");
  impl_->levers = levers;
  impl_->arm_starts = arm_starts;
  impl_->near_between = near_between;
  impl_->near_within = near_within;
  impl_->far_between = far_between;
  impl_->far_within = far_within;
}

bool SceneCheck::clear(const Eigen::VectorXd& state, bool far) {
  Impl& scene = *impl_;
  if (static_cast<std::size_t>(state.size()) != scene.planned.size())
    throw std::invalid_argument("a state has one value per planned joint");
  ++checks;
  scene.place(state);
  const std::size_t count = scene.pairs.size();
  const std::vector<double>& settled = far ? scene.settled_far : scene.settled_near;
  // Whether pair ``p`` keeps its margin: the spheres (squared, compact), then the capsules
  // and boxes, then coal, asked as Pinocchio's computeCollision asks it.
  auto keeps = [&](std::size_t p) {
    if ((scene.centers[scene.pair_first[p]] - scene.centers[scene.pair_second[p]])
            .squaredNorm() > settled[p]) {
      ++pairs_by_volume;
      return true;
    }
    Pair& pair = scene.pairs[p];
    const Geometry& a = scene.geometries[pair.first];
    const Geometry& b = scene.geometries[pair.second];
    const double margin = far ? pair.far_margin : pair.margin;
    if (volume_distance(a, b, margin + 1e-6) > margin + 1e-6) {
      ++pairs_by_volume;
      return true;
    }
    ++pairs_by_coal;
    coal::CollisionRequest& request = scene.request;
    request.security_margin = margin;
    request.distance_upper_bound = margin + 1e-6;
    request.cached_gjk_guess = pair.guess;
    request.cached_support_func_guess = pair.support_guess;
    coal::CollisionResult result;
    (*pair.collide)(coal_pose(a.world), coal_pose(b.world), request, result);
    pair.guess = result.cached_gjk_guess;
    pair.support_guess = result.cached_support_func_guess;
    return !result.isCollision();
  };
  if (count == 0) return true;
  const std::size_t first = scene.last_hit < count ? scene.last_hit : 0;
  if (!keeps(first)) return false;
  for (std::size_t p = 0; p < count; ++p) {
    if (p == first) continue;
    if (!keeps(p)) {
      scene.last_hit = p;
      return false;
    }
  }
  return true;
}

bool SceneCheck::clear_motion(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                              std::int64_t segments) {
  if (from.size() != to.size() || segments < 1)
    throw std::invalid_argument("a motion is two states of one size and at least one segment");
  if (!clear(to, false)) return false;
  // The states between, halves first (OMPL's order: a motion through something usually
  // fails at one of its first few).
  std::vector<std::pair<std::int64_t, std::int64_t>> spans{{1, segments - 1}};
  for (std::size_t next = 0; next < spans.size(); ++next) {
    const auto [low, high] = spans[next];
    if (low > high) continue;
    const std::int64_t middle = (low + high) / 2;
    const double fraction = static_cast<double>(middle) / static_cast<double>(segments);
    if (!clear(Eigen::VectorXd(from + fraction * (to - from)), false)) return false;
    spans.emplace_back(low, middle - 1);
    spans.emplace_back(middle + 1, high);
  }
  return true;
}

std::optional<std::pair<std::int64_t, Eigen::VectorXd>> SceneCheck::first_failure(
    const RowMatrix& path, bool adaptive, const RowMatrix& deviation) {
  if (adaptive) return first_failure_adaptive(path, deviation);
  if (deviation.size() != 0)
    throw std::invalid_argument("a curve (a deviation from the chords) is proven adaptively only");
  Impl& scene = *impl_;
  const Eigen::Index n = static_cast<Eigen::Index>(scene.planned.size());
  if (path.cols() != n || path.rows() < 1)
    throw std::invalid_argument("a path is rows of one value per planned joint");
  if (scene.levers.size() != n) throw std::invalid_argument("set_proof first");
  // Equal steps from a to b that keep the proof with the near (or far) margins.
  auto steps = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b, bool far) {
    const double between = far ? scene.far_between : scene.near_between;
    const double within = far ? scene.far_within : scene.near_within;
    const Eigen::VectorXd moved = scene.levers.cwiseProduct((b - a).cwiseAbs());
    double total = 0.0, largest = 0.0;
    for (std::size_t k = 0; k < scene.arm_starts.size(); ++k) {
      const Eigen::Index from = scene.arm_starts[k];
      const Eigen::Index to =
          k + 1 < scene.arm_starts.size() ? scene.arm_starts[k + 1] : n;
      const double arm = moved.segment(from, to - from).sum();
      total += arm;
      largest = std::max(largest, arm);
    }
    const double needed = std::max(total / (2.0 * between), largest / (2.0 * within));
    return std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(needed)));
  };
  using Failure = std::optional<std::pair<std::int64_t, Eigen::VectorXd>>;
  Eigen::VectorXd first = path.row(0).transpose();
  bool far_before = clear(first, true);
  if (!far_before && !clear(first, false)) return Failure{{0, first}};
  for (Eigen::Index index = 0; index + 1 < path.rows(); ++index) {
    const Eigen::VectorXd start = path.row(index).transpose();
    const Eigen::VectorXd end = path.row(index + 1).transpose();
    const std::int64_t count = steps(start, end, true);
    Eigen::VectorXd a = start;
    for (std::int64_t k = 0; k < count; ++k) {
      const Eigen::VectorXd b =
          k + 1 == count ? end
                         : Eigen::VectorXd(start + (static_cast<double>(k + 1) / count) * (end - start));
      const bool far_after = clear(b, true);
      if (!far_after && !clear(b, false)) return Failure{{index, b}};
      if (!(far_before && far_after)) {  // near something: the clearance's steps
        const std::int64_t fine = steps(a, b, false);
        for (std::int64_t s = 1; s < fine; ++s) {
          const Eigen::VectorXd state = a + (static_cast<double>(s) / fine) * (b - a);
          if (!clear(state, false)) return Failure{{index, state}};
        }
      }
      far_before = far_after;
      a = b;
    }
  }
  return std::nullopt;
}

// The walk of a path with steps sized by the distances found (conservative advancement).
//
// At a checked state each pair p has a slack s_p: its distance less its physics margins
// (a lower bound: the bounding volumes' distance, or coal's distance for the pairs that
// limit the step). Along a segment with joint motion dq, the pair closes by at most
// W_p = sum_k w_pk |dq_k| per unit of the segment (w: the reach of each planned joint to
// the shape it moves relative to the other; 0 for joints that carry both). Between two
// checked states t0 < t1 no point of the pair meets if (t1 - t0) W_p <= s_p(t0) + s_p(t1)
// (from the nearer end, neither closes by more than its own slack). Every checked state
// must also keep the clearance (clear()).
//
// A curve through the rows (a motion that bends away from its chords, each joint within
// ``deviation`` of the chord between two rows at the same fraction of it: one row for every
// chord, or one per chord) is proven the same way with each pair's slack less
// D_p = sum_k w_pk deviation_k, how much nearer the curve
// can bring the pair than the chord does: between two checked states the chord keeps at
// least (s_p(t0) + s_p(t1) - (t1 - t0) W_p) / 2, so the curve keeps more than 0 when
// (t1 - t0) W_p <= (s_p(t0) - D_p) + (s_p(t1) - D_p). The rows themselves are on the curve.
std::optional<std::pair<std::int64_t, Eigen::VectorXd>> SceneCheck::first_failure_adaptive(
    const RowMatrix& path, const RowMatrix& deviation) {
  Impl& scene = *impl_;
  const Eigen::Index n = static_cast<Eigen::Index>(scene.planned.size());
  if (path.cols() != n || path.rows() < 1)
    throw std::invalid_argument("a path is rows of one value per planned joint");
  const bool curved = deviation.size() != 0;
  if (curved && (deviation.cols() != n || !(deviation.array() >= 0.0).all() ||
                 (deviation.rows() != 1 && deviation.rows() != path.rows() - 1)))
    throw std::invalid_argument(
        "a deviation is one value >= 0 per planned joint, in one row or one per chord");
  scene.update_weights();
  using Failure = std::optional<std::pair<std::int64_t, Eigen::VectorXd>>;
  const std::size_t count = scene.pairs.size();
  std::vector<double> slack(count), next_slack(count), closing(count), bent(count, 0.0);
  std::vector<bool> exact(count), next_exact(count);
  // A pair whose exact slack the deviation takes more than half the clearance of at a checked
  // state: the steps would shrink toward nothing there; the curve is refused instead.
  bool too_bent = false;
  auto exact_less_bent = [&](std::size_t p) {
    Pair& pair = scene.pairs[p];
    const double slack_left = scene.exact_slack(pair) - bent[p];
    if (bent[p] > 0.0 && slack_left < 0.5 * (pair.margin - pair.grown)) too_bent = true;
    ++pairs_by_coal;
    return slack_left;
  };
  const double inf = std::numeric_limits<double>::infinity();
  // Slacks at the placed state: lower bounds (the volumes' distance; the slack at the state
  // ``moved`` before, less what the pair may have closed since), coal's distance for the pairs
  // that would limit a step (the smallest slack per closing speed, up to ``horizon``).
  auto measure = [&](std::vector<double>& out, std::vector<bool>& is_exact, double horizon,
                     const std::vector<double>* before, double moved) {
    double best = horizon;
    std::size_t tightest = count;
    double tightest_ratio = inf;
    for (std::size_t p = 0; p < count; ++p) {
      const Pair& pair = scene.pairs[p];
      // The capsules are asked only of pairs the spheres put within the far margin.
      out[p] = volume_distance(scene.geometries[pair.first], scene.geometries[pair.second],
                               pair.far_margin) -
               pair.grown - bent[p];
      if (before != nullptr) out[p] = std::max(out[p], (*before)[p] - moved * closing[p]);
      is_exact[p] = false;
      if (closing[p] > 0.0 && out[p] / closing[p] < tightest_ratio) {
        tightest_ratio = out[p] / closing[p];
        tightest = p;
      }
    }
    if (tightest < count && tightest_ratio < best) {
      out[tightest] = std::max(out[tightest], exact_less_bent(tightest));
      is_exact[tightest] = true;
      best = std::min(best, out[tightest] / closing[tightest]);
    }
    // Pairs whose bound allows at least ``ACCEPT`` of the best step are taken at their bound:
    // a step a little shorter for far fewer distance queries.
    constexpr double ACCEPT = 0.5;
    double bound = best;
    for (std::size_t p = 0; p < count; ++p) {
      if (is_exact[p]) continue;
      if (closing[p] <= 0.0) {
        // Not brought closer by the chord; a curve's deviation may want the exact slack.
        if (out[p] < 0.0) {
          out[p] = std::max(out[p], exact_less_bent(p));
          is_exact[p] = true;
        }
        continue;
      }
      if (out[p] / closing[p] >= ACCEPT * best) {
        bound = std::min(bound, out[p] / closing[p]);
        continue;
      }
      out[p] = std::max(out[p], exact_less_bent(p));
      is_exact[p] = true;
      best = std::min(best, out[p] / closing[p]);
    }
    return std::min(best, bound);  // the largest step (in segments) one side's slack allows
  };
  Eigen::VectorXd first = path.row(0).transpose();
  if (!clear(first, false)) return Failure{{0, first}};
  for (Eigen::Index index = 0; index + 1 < path.rows(); ++index) {
    const Eigen::VectorXd start = path.row(index).transpose();
    const Eigen::VectorXd end = path.row(index + 1).transpose();
    const Eigen::VectorXd motion = (end - start).cwiseAbs();
    for (std::size_t p = 0; p < count; ++p)
      closing[p] = scene.weights.row(static_cast<Eigen::Index>(p)).dot(motion);
    if (curved) {
      const Eigen::Index row = deviation.rows() == 1 ? 0 : index;
      for (std::size_t p = 0; p < count; ++p)
        bent[p] = scene.weights.row(static_cast<Eigen::Index>(p)).dot(deviation.row(row));
    }
    scene.place(start);
    double t = 0.0;
    double reach = measure(slack, exact, 1.0, nullptr, 0.0);
    if (too_bent) return Failure{{index, start}};
    while (t < 1.0) {
      // Try twice what this end's slack allows (the far end likely has as much); else what
      // it allows alone, which needs nothing of the far end but to be clear.
      bool done = false;
      for (int attempt = 0; attempt < 2 && !done; ++attempt) {
        const double step = attempt == 0 ? 2.0 * reach : reach;
        const double next = std::min(1.0, t + std::max(step, 0.0));
        const Eigen::VectorXd state =
            next >= 1.0 ? end : Eigen::VectorXd(start + next * (end - start));
        if (!clear(state, false)) return Failure{{index, state}};
        const double next_reach = measure(next_slack, next_exact, 1.0 - next, &slack, next - t);
        bool proven = true;
        for (std::size_t p = 0; p < count && proven; ++p) {
          // The motion does not bring the two closer (a curve's deviation still may).
          if (closing[p] <= 0.0 && bent[p] == 0.0) continue;
          const double needed = (next - t) * closing[p];
          if (needed <= slack[p] + next_slack[p]) continue;
          if (!next_exact[p]) {
            next_slack[p] = std::max(next_slack[p], exact_less_bent(p));
            next_exact[p] = true;
          }
          proven = needed <= slack[p] + next_slack[p];
        }
        if (too_bent) return Failure{{index, state}};
        if (!proven) {
          // One side's slack alone holds a step of ``reach``: not proven then would be a
          // fault of the bounds; refuse the path rather than pass it.
          if (attempt == 1 || next - t <= reach) return Failure{{index, state}};
          continue;
        }
        t = next;
        reach = next_reach;
        std::swap(slack, next_slack);
        std::swap(exact, next_exact);
        done = true;
      }
    }
  }
  return std::nullopt;
}

}  // namespace armfleet
