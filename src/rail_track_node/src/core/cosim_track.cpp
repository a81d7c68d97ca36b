// Track side of the co-simulation (see cosim_track.hpp).
#include "rail_track_node/cosim_track.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <rail_contact/beam_shape.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/scene_loader.hpp>

#include "rail_track_node/elements.hpp"

namespace rail {
namespace track {

namespace rc = rail::contact;
namespace cc = rail::core::coupling;
using rail::core::Scene;
using rail::core::SceneError;

CosimTrack::CosimTrack(const Scene& scene, const CosimTrackOptions& options) {
  if (!scene.has_vehicle) throw SceneError(scene.file + ": the co-simulation track needs a vehicle (none in the scene)");
  if (!scene.needs_track_node())
    throw SceneError(scene.file + ": effects.track_model: rigid runs the vehicle alone; the track side needs "
                                  "rigid_fe or flexible");
  const int n_wheels = scene.wheel_count();
  if (n_wheels <= 0) {
    std::ostringstream os;
    os << scene.file << ": vehicle.wheelsets: must be > 0, got " << scene.vehicle.wheelsets;
    throw SceneError(os.str());
  }

  // Geometry (both cases), FE track (flexible only).
  double section_depth = rc::uic60::kCentroidDepth;  // rail section centre below the head top, as the vehicle
  if (scene.runs_fe_integration()) {
    fe_ = std::make_unique<SceneTrack>(buildSceneTrack(scene, options.track));
    geometry_ = &fe_->geometry;
    // The contact's section centre on the FE beam axis (the rail centroid node).
    section_depth = fe_->rail_height - fe_->model.data.layout.rail_centroid_height;
  } else {
    rigid_geometry_ = std::make_unique<rc::TrackGeometry>(rail::core::build_track_geometry(scene));
    geometry_ = rigid_geometry_.get();
  }

  // Contact model, built as the vehicle side builds it on the rigid track.
  try {
    wheel_profile_ = scene.vehicle.wheel_profile_file.empty() ? rc::makeS1002()
                                                              : rc::loadWheelProfile(scene.vehicle.wheel_profile_file.path);
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    throw SceneError(scene.file + ": vehicle.wheel_profile: " + e.what());
  }
  rail_profile_ = rail::core::rail_profile_curve(scene);
  rc::WheelContactOptions contact = options.contact;
  contact.flange_contact = scene.effects.flange_contact;
  contact.spin = scene.effects.spin_creepage;
  contact.creep_law = rc::CreepLaw::kPolach;  // core::CreepLaw has Polach only
  contact_model_ = std::make_unique<rc::WheelContactModel>(wheel_profile_, scene.vehicle.nominal_radius, rail_profile_,
                                                           Eigen::Vector2d(0.0, -section_depth), contact);
  work_.assign(static_cast<std::size_t>(n_wheels), rc::WheelContactWork());
  result_.assign(static_cast<std::size_t>(n_wheels), rc::WheelContactResult());
  seen_.assign(static_cast<std::size_t>(n_wheels), 0);

  if (!fe_) return;

  // Newmark at the track step, from the static equilibrium under the track's own weight.
  const TrackModel& model = fe_->model;
  const TrackMesh& mesh = model.mesh;
  integrator_ = std::make_unique<NewmarkIntegrator>(model.system, scene.solver.track_step, options.include_gravity);
  Eigen::VectorXd d0 = options.include_gravity ? staticGravityDeflection(model.system)
                                               : Eigen::VectorXd::Zero(model.system.size());
  state_ = integrator_->initialState(d0);
  // Two contacts per wheel, each spread over the 12 DOFs of one rail element.
  loads_ = std::make_unique<NodalLoads>(24 * n_wheels + 1);

  // The rails as the contact search sees them: the FE rail beams, nodes equally spaced in s.
  std::array<std::vector<rc::RailBeamElement>, 2> elements;
  for (int r = 0; r < 2; ++r) {
    for (int b : mesh.rail_beams[r]) {
      rc::RailBeamElement e;
      e.length = mesh.beams[static_cast<std::size_t>(b)].length;
      e.R_local_to_world = mesh.beams[static_cast<std::size_t>(b)].R_local_to_world;
      elements[r].push_back(e);
    }
    rail_dofs_[r].resize(6 * mesh.rail_nodes[r].size());
    for (std::size_t k = 0; k < mesh.rail_nodes[r].size(); ++k)
      for (int j = 0; j < 6; ++j) rail_dofs_[r][6 * k + j] = mesh.dofIndex(mesh.rail_nodes[r][k], j);
  }
  deformation_ = std::make_unique<rc::BeamRailDeformation>(
      mesh.s_start, mesh.sleeper_spacing / mesh.rail_elements_between_sleepers, std::move(elements));
  fillDeformation();
}

CosimTrack::~CosimTrack() = default;

const NewmarkState* CosimTrack::state() const { return fe_ ? &state_ : nullptr; }

void CosimTrack::fillDeformation() noexcept {
  for (int r = 0; r < 2; ++r) {
    const rc::RailSide side = r == 0 ? rc::RailSide::kLeft : rc::RailSide::kRight;
    double* q = deformation_->nodalDisplacements(side);
    double* qd = deformation_->nodalVelocities(side);
    const std::vector<int>& dofs = rail_dofs_[r];
    for (std::size_t i = 0; i < dofs.size(); ++i) {
      const int g = dofs[i];
      q[i] = g >= 0 ? state_.d(g) : 0.0;
      qd[i] = g >= 0 ? state_.v(g) : 0.0;
    }
  }
}

CosimStepStatus CosimTrack::step(const cc::WheelStateFrame& states, cc::WrenchFrame& out) noexcept {
  const int n = wheelCount();
  if (static_cast<int>(states.count) != n || states.capacity() < n || out.capacity() < n)
    return CosimStepStatus::kWrongWheelCount;
  for (int i = 0; i < n; ++i) seen_[static_cast<std::size_t>(i)] = 0;
  for (int i = 0; i < n; ++i) {
    const std::uint32_t id = states.wheels[static_cast<std::size_t>(i)].id;
    if (id >= static_cast<std::uint32_t>(n) || seen_[id]) return CosimStepStatus::kBadWheelId;
    seen_[id] = 1;
  }

  // Contact of every wheel on the rails at the start of the step.
  if (fe_) loads_->clear();
  for (int i = 0; i < n; ++i) {
    const cc::WheelState& in = states.wheels[static_cast<std::size_t>(i)];
    const std::size_t id = in.id;
    const rc::RailSide side = (in.id % 2 == 0) ? rc::RailSide::kLeft : rc::RailSide::kRight;
    rc::WheelState ws;
    ws.p_centre_in_world = in.p_wheel_in_world;
    ws.R_wheelset_to_world = in.q_wheelset_to_world.normalized().toRotationMatrix();
    ws.v_centre_in_world = in.v_wheel_in_world;
    ws.omega_in_world = in.omega_wheelset_in_world;
    ws.s_hint = in.arc_length;
    rc::WheelContactResult& res = result_[id];
    if (fe_) {
      contact_model_->evaluate(ws, side, *geometry_, *deformation_, work_[id], res);
      const int rail = side == rc::RailSide::kLeft ? kLeftRail : kRightRail;
      for (int c = 0; c < 2; ++c) {
        const rc::ContactPointResult& cp = res.contact[c];
        if (!cp.active) continue;
        // Eq. 15 for this contact about its own section centre, then eq. 16 onto the element's nodes.
        addRailPointLoad(fe_->model.mesh, rail, cp.s_r, cp.rail_wrench.force_in_world,
                         cp.rail_wrench.moment_in_world, *loads_);
      }
    } else {
      contact_model_->evaluate(ws, side, *geometry_, rc::RigidRailDeformation(), work_[id], res);
    }
    cc::WheelWrench& w = out.wheels[static_cast<std::size_t>(i)];
    w.id = in.id;
    w.f_wheel_in_world = res.wheel_centre.force_in_world;
    w.n_wheel_in_world = ws.R_wheelset_to_world * res.wheel_centre.moment_in_wheelset;
  }
  out.count = static_cast<std::uint32_t>(n);
  out.step = states.step;
  out.time = states.time;
  out.scene_hash = states.scene_hash;

  // Flexible: advance the FE track to t_k with these contact loads, then expose its rails to the next step.
  if (fe_ && states.step > 0) {
    integrator_->step(state_, *loads_);
    ++newmark_steps_;
    fillDeformation();
  }
  ++frames_;
  return CosimStepStatus::kOk;
}

int CosimTrack::addSection(double s) {
  Section sec;
  sec.s = s;
  if (!fe_) {
    if (!(s >= geometry_->sStart() && s <= geometry_->sEnd())) {
      std::ostringstream os;
      os << "deflection section at s = " << s << " m is not on the track [" << geometry_->sStart() << ", "
         << geometry_->sEnd() << "] m";
      throw std::runtime_error(os.str());
    }
    for (int r = 0; r < 2; ++r) {
      sec.rail[r].dofs.fill(-1);
      sec.rail[r].P_u.setZero();
      sec.rail[r].P_theta.setZero();
    }
    sections_.push_back(sec);
    return static_cast<int>(sections_.size()) - 1;
  }
  const TrackMesh& mesh = fe_->model.mesh;
  rc::TrackPoint tp;
  for (int r = 0; r < 2; ++r) {
    int beam = 0;
    double xi = 0.0;
    if (!mesh.locateRail(r, s, beam, xi)) {
      std::ostringstream os;
      os << "deflection section at s = " << s << " m is not on the meshed rails [" << mesh.s_start << ", "
         << mesh.railNodeS(static_cast<int>(mesh.rail_nodes[r].size()) - 1) << "] m";
      throw std::runtime_error(os.str());
    }
    geometry_->centre(s, tp);
    const BeamElement& b = mesh.beams[static_cast<std::size_t>(beam)];
    rc::Matrix3x12 N_u, N_theta;
    rc::beamShapeDisplacement(xi, b.length, N_u);
    rc::beamShapeRotation(xi, b.length, N_theta);
    const Matrix12d T = beamWorldToLocal(b.R_local_to_world);
    const Eigen::Matrix3d R_local_to_track = tp.R_track_to_world.transpose() * b.R_local_to_world;
    RailProbe& p = sec.rail[r];
    p.P_u = R_local_to_track * N_u * T;
    p.P_theta = R_local_to_track * N_theta * T;
    for (int d = 0; d < 6; ++d) {
      p.dofs[d] = mesh.dofIndex(b.node_i, d);
      p.dofs[6 + d] = mesh.dofIndex(b.node_j, d);
    }
  }
  sections_.push_back(sec);
  return static_cast<int>(sections_.size()) - 1;
}

void CosimTrack::sectionDeflection(int i, RailSectionDeflection& out) const {
  sectionDeflection(i, state_.d, out);
}

void CosimTrack::sectionDeflection(int i, const Eigen::VectorXd& d, RailSectionDeflection& out) const {
  const Section& sec = sections_[static_cast<std::size_t>(i)];
  out.s = sec.s;
  for (int r = 0; r < 2; ++r) {
    const RailProbe& p = sec.rail[r];
    Eigen::Matrix<double, 12, 1> d_e;
    for (int k = 0; k < 12; ++k) d_e(k) = (fe_ && p.dofs[k] >= 0) ? d(p.dofs[k]) : 0.0;
    out.displacement[r].noalias() = p.P_u * d_e;
    out.rotation[r].noalias() = p.P_theta * d_e;
  }
}

}  // namespace track
}  // namespace rail
