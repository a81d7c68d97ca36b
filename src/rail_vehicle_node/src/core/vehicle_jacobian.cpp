#include "rail_vehicle_node/vehicle_jacobian.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

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
  for (int c = 0; c < pattern.nBodyColours(); ++c) {
    const std::vector<int>& bodies = pattern.colourBodies(c);
    const std::vector<char>& live = pattern.liveElements(c);
    for (int l = 0; l < 13; ++l) {
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
  return evaluations;
}

}  // namespace rail::vehicle
