#include "rail_vehicle_node/vehicle_jacobian.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "rail_vehicle_node/multibody_dynamics.hpp"

namespace rail::vehicle {

int JacobianPattern::column(const VehicleModel& model, int b, int l) const {
  return l < 7 ? VehicleModel::positionOffset(b) + l : model.velocityOffset(b) + (l - 7);
}

JacobianPattern::JacobianPattern(const VehicleModel& model) {
  const int n_b = model.nBodies();
  n_ = model.stateSize();
  // Bodies coupled by the range-space solve: the body's joint cluster, or the body alone.
  std::vector<std::vector<int>> cluster_of(static_cast<std::size_t>(n_b));
  for (int b = 0; b < n_b; ++b) {
    const int c = model.clusterOfBody()[static_cast<std::size_t>(b)];
    cluster_of[static_cast<std::size_t>(b)] =
        c < 0 ? std::vector<int>{b} : model.constraintClusters()[static_cast<std::size_t>(c)].bodies;
  }
  // Row bodies of each body's columns, and the bodies each force element touches.
  std::vector<std::set<int>> rows_of(static_cast<std::size_t>(n_b));
  for (int b = 0; b < n_b; ++b) {
    for (int c : cluster_of[static_cast<std::size_t>(b)]) rows_of[static_cast<std::size_t>(b)].insert(c);
  }
  const auto& elements = model.forceElements();
  std::vector<std::set<int>> touches(elements.size());
  for (std::size_t e = 0; e < elements.size(); ++e) {
    std::vector<std::vector<int>> groups;
    elements[e]->couplingGroups(groups);
    for (const auto& group : groups) {
      for (int b : group) {
        touches[e].insert(b);
        for (int c : group) {
          for (int r : cluster_of[static_cast<std::size_t>(c)]) rows_of[static_cast<std::size_t>(b)].insert(r);
        }
      }
    }
  }
  // Greedy body colouring: a colour's bodies have disjoint row sets.
  body_colour_.assign(static_cast<std::size_t>(n_b), -1);
  std::vector<std::set<int>> colour_rows;
  for (int b = 0; b < n_b; ++b) {
    const auto& rows = rows_of[static_cast<std::size_t>(b)];
    int colour = 0;
    for (; colour < static_cast<int>(colour_rows.size()); ++colour) {
      const auto& taken = colour_rows[static_cast<std::size_t>(colour)];
      if (std::none_of(rows.begin(), rows.end(), [&taken](int r) { return taken.count(r) > 0; })) break;
    }
    if (colour == static_cast<int>(colour_rows.size())) {
      colour_rows.emplace_back();
      colour_bodies_.emplace_back();
    }
    colour_rows[static_cast<std::size_t>(colour)].insert(rows.begin(), rows.end());
    colour_bodies_[static_cast<std::size_t>(colour)].push_back(b);
    body_colour_[static_cast<std::size_t>(b)] = colour;
  }
  n_body_colours_ = static_cast<int>(colour_bodies_.size());
  for (const auto& bodies : colour_bodies_) {
    std::vector<char> live(elements.size(), 0);
    for (std::size_t e = 0; e < elements.size(); ++e) {
      for (int b : bodies) {
        if (touches[e].count(b) > 0) live[e] = 1;
      }
    }
    live_elements_.push_back(live);
  }
  // Columns: velocity rows of the row bodies, the body's own position rows that depend on the coordinate
  // (r_dot = v; p_dot from p and omega'), and the diagonal.
  std::vector<std::set<int>> column_rows(static_cast<std::size_t>(n_));
  for (int b = 0; b < n_b; ++b) {
    for (int l = 0; l < 13; ++l) {
      std::set<int>& rows = column_rows[static_cast<std::size_t>(column(model, b, l))];
      rows.insert(column(model, b, l));
      for (int r : rows_of[static_cast<std::size_t>(b)]) {
        for (int i = 0; i < 6; ++i) rows.insert(model.velocityOffset(r) + i);
      }
      if (l >= 3 && l < 7) {
        for (int i = 0; i < 4; ++i) rows.insert(VehicleModel::eulerOffset(b) + i);
      } else if (l >= 7 && l < 10) {
        rows.insert(VehicleModel::positionOffset(b) + (l - 7));
      } else if (l >= 10) {
        for (int i = 0; i < 4; ++i) rows.insert(VehicleModel::eulerOffset(b) + i);
      }
    }
  }
  col_start_.assign(static_cast<std::size_t>(n_ + 1), 0);
  for (int j = 0; j < n_; ++j) {
    const auto& rows = column_rows[static_cast<std::size_t>(j)];
    row_index_.insert(row_index_.end(), rows.begin(), rows.end());
    col_start_[static_cast<std::size_t>(j + 1)] = static_cast<int>(row_index_.size());
  }
}

JacobianWork::JacobianWork(const VehicleModel& model, const JacobianPattern& pattern)
    : y_perturbed(Eigen::VectorXd::Zero(model.stateSize())),
      f0(Eigen::VectorXd::Zero(model.stateSize())),
      f(Eigen::VectorXd::Zero(model.stateSize())),
      increment(Eigen::VectorXd::Zero(model.stateSize())),
      element_g(Eigen::MatrixXd::Zero(model.nVelocities(), static_cast<Eigen::Index>(model.forceElements().size()))),
      all_live(model.forceElements().size(), 1),
      none_live(model.forceElements().size(), 0),
      values(static_cast<std::size_t>(pattern.nonzeros()), 0.0) {}

int evaluateJacobian(const VehicleModel& model, const JacobianPattern& pattern, double t,
                     const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& weight,
                     double min_increment, VehicleData& data, JacobianWork& work, core::CostClock* cost) {
  const auto& elements = model.forceElements();
  for (const auto& e : elements) e->saveWorkState();
  int evaluations = 0;
  {
    // Each element's contribution at y, then f(y) from them (the same sums as the perturbed evaluations).
    core::CostClock::Scope timing(cost, core::CostClock::kVehicleJacobian);
    data.time = t;
    computeKinematics(model, y, data);
    computeElementForces(model, data, work.element_g);
    for (const auto& e : elements) e->restoreWorkState();
    computeDerivativesPartial(model, t, y, work.f0, data, work.none_live, work.element_g);
    ++evaluations;
  }
  const double srur = std::sqrt(std::numeric_limits<double>::epsilon());
  for (int j = 0; j < pattern.size(); ++j) {
    const double inc = std::max(srur * std::abs(y[j]), min_increment / weight[j]);
    work.y_perturbed[j] = y[j] + inc;
    work.increment[j] = work.y_perturbed[j] - y[j];  // the representable increment
  }
  Eigen::VectorXd& yp = work.y_perturbed;
  yp = y;
  const auto& col_start = pattern.colStart();
  const auto& row_index = pattern.rowIndex();
  // The velocity columns (l = 7..12) of every colour first: their positions are y's, so the range-space
  // solve keeps the cluster factors f0's evaluation formed (each evaluation is independent of the order).
  struct ReuseReset {  // no stale factors for the next caller, however this returns
    VehicleData& data;
    ~ReuseReset() { data.reuse_cluster_factors = false; }
  } reuse_reset{data};
  for (int pass = 0; pass < 2; ++pass) {
    const bool velocities = pass == 0;
    data.reuse_cluster_factors = velocities;
    for (int c = 0; c < pattern.nBodyColours(); ++c) {
      const std::vector<int>& bodies = pattern.colourBodies(c);
      const std::vector<char>& live = pattern.liveElements(c);
      for (int l = velocities ? 7 : 0; l < (velocities ? 13 : 7); ++l) {
        for (int b : bodies) {
          const int j = pattern.column(model, b, l);
          yp[j] = y[j] + work.increment[j];
        }
        {
          core::CostClock::Scope timing(cost, core::CostClock::kVehicleJacobian);
          computeDerivativesPartial(model, t, yp, work.f, data, live, work.element_g);
          ++evaluations;
        }
        for (std::size_t e = 0; e < elements.size(); ++e) {
          if (live[e] != 0) elements[e]->restoreWorkState();
        }
        for (int b : bodies) {
          const int j = pattern.column(model, b, l);
          const double inverse = 1.0 / work.increment[j];
          for (int k = col_start[static_cast<std::size_t>(j)]; k < col_start[static_cast<std::size_t>(j + 1)]; ++k) {
            const int i = row_index[static_cast<std::size_t>(k)];
            work.values[static_cast<std::size_t>(k)] = (work.f[i] - work.f0[i]) * inverse;
          }
          yp[j] = y[j];
        }
      }
    }
  }
  return evaluations;
}

namespace {

// Positions of the rows first_row .. first_row + size - 1 in every column that holds them, checking that
// they come as one block (rows are sorted within a column).
std::vector<int> blockPositions(const JacobianPattern& pattern, int first_row, int size) {
  std::vector<int> at;
  const auto& start = pattern.colStart();
  const auto& rows = pattern.rowIndex();
  for (int j = 0; j < pattern.size(); ++j) {
    for (int k = start[static_cast<std::size_t>(j)]; k < start[static_cast<std::size_t>(j + 1)]; ++k) {
      if (rows[static_cast<std::size_t>(k)] != first_row) continue;
      for (int i = 1; i < size; ++i) {
        if (k + i >= start[static_cast<std::size_t>(j + 1)] || rows[static_cast<std::size_t>(k + i)] != first_row + i) {
          throw std::invalid_argument("spin transport: rows " + std::to_string(first_row) + ".." +
                                      std::to_string(first_row + size - 1) + " are not one block in column " +
                                      std::to_string(j));
        }
      }
      at.push_back(k);
    }
  }
  return at;
}

// Columns first .. first + size - 1 must hold the same rows, so that they can be mixed entry by entry.
void requireSameRows(const JacobianPattern& pattern, int first, int size) {
  const auto& start = pattern.colStart();
  const auto& rows = pattern.rowIndex();
  const auto begin = [&](int j) { return rows.begin() + start[static_cast<std::size_t>(j)]; };
  for (int l = 1; l < size; ++l) {
    if (!std::equal(begin(first), begin(first + 1), begin(first + l), begin(first + l + 1))) {
      throw std::invalid_argument("spin transport: columns " + std::to_string(first) + " and " +
                                  std::to_string(first + l) + " do not hold the same rows");
    }
  }
}

// The turn about y taking p_from to p_to (p_to = p_from (x) q_y), as Euler parameters of the y turn alone.
Vector4 turnAboutY(const Vector4& p_from, const Vector4& p_to) {
  const Vector4 conj(p_from[0], -p_from[1], -p_from[2], -p_from[3]);
  const Vector4 relative = quaternionProduct(conj, p_to);
  const double half = std::atan2(relative[2], relative[0]);
  return Vector4(std::cos(half), 0.0, std::sin(half), 0.0);
}

}  // namespace

SpinTransport::SpinTransport(const VehicleModel& model, const JacobianPattern& pattern,
                             const std::vector<int>& spin_bodies)
    : col_start_(pattern.colStart()) {
  for (int b : spin_bodies) {
    if (b < 0 || b >= model.nBodies()) {
      throw std::invalid_argument("spin transport: no body " + std::to_string(b));
    }
    SpinBody sb;
    sb.euler_column = VehicleModel::eulerOffset(b);
    sb.omega_column = model.angularVelocityOffset(b);
    requireSameRows(pattern, sb.euler_column, 4);
    requireSameRows(pattern, sb.omega_column, 3);
    sb.euler_rows_at = blockPositions(pattern, sb.euler_column, 4);
    sb.omega_rows_at = blockPositions(pattern, sb.omega_column, 3);
    bodies_.push_back(std::move(sb));
  }
}

void SpinTransport::setReference(const Eigen::Ref<const Eigen::VectorXd>& y) {
  for (SpinBody& sb : bodies_) sb.p_reference = y.segment<4>(sb.euler_column).normalized();
}

double SpinTransport::turn(int k, const Eigen::Ref<const Eigen::VectorXd>& y) const {
  const SpinBody& sb = bodies_[static_cast<std::size_t>(k)];
  const Vector4 q = turnAboutY(sb.p_reference, y.segment<4>(sb.euler_column).normalized());
  return 2.0 * std::atan2(q[2], q[0]);
}

void SpinTransport::transport(const Eigen::Ref<const Eigen::VectorXd>& y, const std::vector<double>& values,
                              std::vector<double>& values_out) const {
  std::copy(values.begin(), values.end(), values_out.begin());
  for (const SpinBody& sb : bodies_) {
    const Vector4 q = turnAboutY(sb.p_reference, y.segment<4>(sb.euler_column).normalized());
    // T on the Euler parameters: p -> p (x) q, column m of T_p being e_m (x) q; on omega': R_y^T.
    Eigen::Matrix4d t_euler;
    for (int m = 0; m < 4; ++m) t_euler.col(m) = quaternionProduct(Vector4::Unit(m), q);
    const Matrix3 t_omega = rotationFromEulerParameters(q).transpose();
    // Columns: (J T^T)(:, l) = sum_m J(:, m) T(l, m).
    auto mixColumns = [&](int first, const auto& t, auto size_tag) {
      constexpr int kSize = decltype(size_tag)::value;
      const int length = col_start_[static_cast<std::size_t>(first + 1)] - col_start_[static_cast<std::size_t>(first)];
      for (int k = 0; k < length; ++k) {
        Eigen::Matrix<double, kSize, 1> entries;
        for (int m = 0; m < kSize; ++m) {
          entries[m] = values_out[static_cast<std::size_t>(col_start_[static_cast<std::size_t>(first + m)] + k)];
        }
        const Eigen::Matrix<double, kSize, 1> mixed = t * entries;
        for (int l = 0; l < kSize; ++l) {
          values_out[static_cast<std::size_t>(col_start_[static_cast<std::size_t>(first + l)] + k)] = mixed[l];
        }
      }
    };
    // Rows: (T J)(l, :) = sum_m T(l, m) J(m, :).
    auto mixRows = [&](const std::vector<int>& at, const auto& t, auto size_tag) {
      constexpr int kSize = decltype(size_tag)::value;
      for (int k : at) {
        Eigen::Map<Eigen::Matrix<double, kSize, 1>> block(&values_out[static_cast<std::size_t>(k)]);
        const Eigen::Matrix<double, kSize, 1> mixed = t * block;
        block = mixed;
      }
    };
    mixColumns(sb.euler_column, t_euler, std::integral_constant<int, 4>());
    mixColumns(sb.omega_column, t_omega, std::integral_constant<int, 3>());
    mixRows(sb.euler_rows_at, t_euler, std::integral_constant<int, 4>());
    mixRows(sb.omega_rows_at, t_omega, std::integral_constant<int, 3>());
  }
}

}  // namespace rail::vehicle
