// Hanging (voided) sleepers: the ballast elements of a mesh marked unilateral (SpringDamperElement) bear
// along their local z only in compression, once the void between the sleeper and the ballast has closed.
// The track stays one constant linear system: K and C hold each such element as if its void had closed,
// and the difference between the element's real force and that linear one enters each Newmark step as a
// load, evaluated on the state predicted at the end of the step (as the contact geometry is). A void that
// never opens therefore gives exactly the linear track. ROS-free; see doc/fe.md "Hanging sleepers".
#pragma once

#include <Eigen/Core>

#include <array>
#include <vector>

#include "rail_track_node/newmark.hpp"
#include "rail_track_node/track_mesh.hpp"
#include "rail_track_node/track_model.hpp"

namespace rail {
namespace track {

class HangingSupports {
 public:
  /// Indexes the unilateral ballast elements of mesh (set-up; allocates). Empty when there are none.
  explicit HangingSupports(const TrackMesh& mesh);

  bool empty() const { return elements_.empty(); }
  int count() const { return static_cast<int>(elements_.size()); }
  /// Entries one addLoads() call adds at most.
  int loadCapacity() const { return 6 * count(); }

  /// Lift z (m, along the element's local z, up) of element e's point on the sleeper from displacements d
  /// (plus d_static when not null), and the force the ballast puts on the sleeper along local z (N, >= 0):
  /// max(0, k p + c p'), p = -(z + gap) the closure beyond the void, p' = -z' (lift() of the velocities).
  double lift(int e, const Eigen::VectorXd& d, const Eigen::VectorXd* d_static) const noexcept;
  double bearingForce(int e, double z, double z_dot) const noexcept;
  double gap(int e) const noexcept { return elements_[static_cast<std::size_t>(e)].gap; }

  /// Adds, per element, the nodal loads of (real force - linear force - baseline) along local z, evaluated
  /// at the predicted state d + dt v (plus d_static) with velocity v. Returns false if loads is full.
  /// No allocation.
  bool addLoads(const Eigen::VectorXd& d, const Eigen::VectorXd& v, const Eigen::VectorXd* d_static, double dt,
                NodalLoads& loads) const noexcept;
  /// Makes the loads relative to the static state d_static at rest: a track window integrates w from its
  /// self-weight state d_g (K d_g = f_g + loads(d_g)), so its step loads are loads(d_g + w) - loads(d_g).
  void setBaseline(const Eigen::VectorXd& d_static);

  /// Static equilibrium K d = f + loads(d, at rest) of the piecewise-linear track: the set of closed voids
  /// is found by repeated linear solves (set-up; factorises K once per set). Throws std::runtime_error when
  /// the set does not settle within 100 solves.
  Eigen::VectorXd solveStatic(const LinearSystem& sys, const Eigen::VectorXd& f) const;

 private:
  struct Element {
    std::array<int, 6> dofs;        // free DOFs of the sleeper node (translations, rotations); -1 fixed
    Eigen::Matrix<double, 6, 1> b;  // lift of the element's point per DOF: [n; r x n]
    double k = 0.0, c = 0.0, gap = 0.0;
    double baseline = 0.0;  // setBaseline: the load at the static state, N
  };
  double correction(const Element& el, double z, double z_dot) const noexcept;
  std::vector<Element> elements_;
};

/// The track's static state under f (K d = f) with hanging sleepers if `mesh` has any, else the linear one.
Eigen::VectorXd solveStaticWithSupports(const TrackMesh& mesh, const LinearSystem& sys, const Eigen::VectorXd& f);

}  // namespace track
}  // namespace rail
