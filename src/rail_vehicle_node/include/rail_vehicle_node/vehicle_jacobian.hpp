// Sparse Jacobian df/dy of the vehicle's right-hand side (multibody_dynamics.hpp) by a coloured
// difference quotient over the sparsity that the model's topology implies.
//
// Sparsity, body by body: the velocity rows of body r depend on the state of body b when b's joint
// cluster (VehicleModel::constraintClusters; the range-space solve couples a cluster's bodies) contains r,
// or when a force element couples b with a body of r's cluster (ForceElement::couplingGroups; the contact
// couples each wheelset with itself only). Position rows: r_dot from v, p_dot from p and omega'. Every
// diagonal entry is kept (CVODE forms I - gamma J in place).
// Colouring: bodies whose row sets are disjoint share a colour (greedy); column l of every body of one
// colour is perturbed together, so a Jacobian costs 13 x (body colours) evaluations instead of 13 n (the
// paper coach: 6 body colours, 78 instead of 195). An evaluation re-evaluates only the force elements that
// touch a perturbed body, the others keep their contribution at the unperturbed state: the contact is
// evaluated in 13 of them. The elements' work states (the contact's warm starts and impact memories) are
// saved before and restored after, so a Jacobian leaves the run unchanged.
//
// Model/Data split: JacobianPattern is built once from a finalised model; JacobianWork is the caller's
// preallocated scratch. No allocation in evaluateJacobian.
#pragma once

#include <Eigen/Core>
#include <vector>

#include <rail_core/cost_profile.hpp>

#include "rail_vehicle_node/vehicle_data.hpp"
#include "rail_vehicle_node/vehicle_model.hpp"

namespace rail::vehicle {

class JacobianPattern {
 public:
  explicit JacobianPattern(const VehicleModel& model);

  int size() const { return n_; }  // state size 13 n
  int nonzeros() const { return static_cast<int>(row_index_.size()); }
  // Compressed sparse columns: rows of column j are row_index()[col_start()[j] .. col_start()[j + 1]).
  const std::vector<int>& colStart() const { return col_start_; }
  const std::vector<int>& rowIndex() const { return row_index_; }
  int nBodyColours() const { return n_body_colours_; }
  int nColours() const { return 13 * n_body_colours_; }
  const std::vector<int>& bodyColour() const { return body_colour_; }
  // Bodies of body colour c.
  const std::vector<int>& colourBodies(int c) const { return colour_bodies_[static_cast<std::size_t>(c)]; }
  // Force elements re-evaluated when body colour c is perturbed (1) or kept (0), per element.
  const std::vector<char>& liveElements(int c) const { return live_elements_[static_cast<std::size_t>(c)]; }
  // State column of local coordinate l (0..12: r, p, r_dot, omega') of body b.
  int column(const VehicleModel& model, int b, int l) const;

 private:
  int n_ = 0;
  int n_body_colours_ = 0;
  std::vector<int> col_start_, row_index_;
  std::vector<int> body_colour_;
  std::vector<std::vector<int>> colour_bodies_;
  std::vector<std::vector<char>> live_elements_;
};

struct JacobianWork {
  JacobianWork(const VehicleModel& model, const JacobianPattern& pattern);
  Eigen::VectorXd y_perturbed, f0, f, increment;
  Eigen::MatrixXd element_g;  // 6n x elements: each force element's contribution at the unperturbed state
  std::vector<char> all_live, none_live;
  std::vector<double> values;  // nonzeros in the pattern's order
};

// Fills work.values with the forward difference quotient of f at (t, y), column j perturbed by
// inc_j = max(sqrt(eps) |y_j|, min_increment / weight_j) (CVODE's rule for its banded and dense quotients;
// weight = CVODE's error weights, 1/(rtol |y| + atol)). Leaves data and the elements' work states as they
// were before the call. cost: each evaluation timed as kVehicleJacobian (null: no timing).
// Returns the number of right-hand-side evaluations (partial ones included).
int evaluateJacobian(const VehicleModel& model, const JacobianPattern& pattern, double t,
                     const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& weight,
                     double min_increment, VehicleData& data, JacobianWork& work, core::CostClock* cost = nullptr);

// A Jacobian carried along with the wheelsets' spin. A wheelset turns about its axle (its body y axis) at
// V / r, 69 rad/s at 110 km/h, while the rest of its state changes slowly; with body-frame angular
// velocities and Euler parameters as states its rows and columns of J turn with it, and a Jacobian a few
// steps old (0.2-0.3 rad) no longer lets Newton converge (doc/simulator.md). A body whose dynamics do not
// change when it turns about its own y axis (inertia symmetric about y, joints revolute about y, wheels of
// revolution, loads on the axle line) has f(T y) = T f(y) for T turning its Euler parameters
// p -> p (x) q_y(phi) and its angular velocity omega' -> R_y(phi)^T omega'; so J(T y) = T J(y) T^T.
// For a body that is not exactly invariant the carried J is only an approximation: Newton may then need a
// new evaluation, the solution is the same.
class SpinTransport {
 public:
  // Throws std::invalid_argument when a body's Euler-parameter or angular-velocity columns do not share
  // their rows in the pattern (never for a JacobianPattern of the same model).
  SpinTransport(const VehicleModel& model, const JacobianPattern& pattern, const std::vector<int>& spin_bodies);

  bool empty() const { return bodies_.empty(); }
  // The state the carried Jacobian was evaluated at.
  void setReference(const Eigen::Ref<const Eigen::VectorXd>& y);
  // values_out = T values T^T in the pattern's order, T turning each spin body about its y axis by its turn
  // from the reference state to y. values_out must have the pattern's size; no allocation.
  void transport(const Eigen::Ref<const Eigen::VectorXd>& y, const std::vector<double>& values,
                 std::vector<double>& values_out) const;
  // The turn about y of spin body k from the reference to y [rad], in (-pi, pi].
  double turn(int k, const Eigen::Ref<const Eigen::VectorXd>& y) const;

 private:
  struct SpinBody {
    int euler_column = 0;  // first of the 4 Euler-parameter columns (and rows)
    int omega_column = 0;  // first of the 3 angular-velocity columns (and rows)
    Vector4 p_reference = Vector4(1.0, 0.0, 0.0, 0.0);
    std::vector<int> euler_rows_at;  // positions of the 4-row Euler block, one per column holding it
    std::vector<int> omega_rows_at;  // positions of the 3-row angular-velocity block
  };
  std::vector<SpinBody> bodies_;
  std::vector<int> col_start_;
};

}  // namespace rail::vehicle
