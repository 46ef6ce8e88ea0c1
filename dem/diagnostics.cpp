// The step's health (STYLE.md habit 8): the checks at the end of a step and, on the rare step that
// fails one, the diagnosis that names the offending particle, the time and the knob to turn.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>

#include "dem/internal_phases.h"
#include "dem/internal_workspace.h"

namespace dem::internal {

namespace {

// The offending particle with the smallest persistent id: (id, storage index), or (-1, 0).
template <typename Pred>
std::pair<int64_t, size_t> FirstById(const Particles& p, Pred pred) {
  int64_t best = -1;
  size_t at = 0;
  for (size_t i = 0; i < p.size(); ++i)
    if (pred(i) && (best < 0 || p.id[i] < best)) {
      best = p.id[i];
      at = i;
    }
  return std::make_pair(best, at);
}

// Where particle i is, for a message.
std::string Where(const Particles& p, size_t i) {
  std::ostringstream s;
  s.precision(4);
  s << "(radius " << p.radius[i] << " m at [" << p.x[i].x << ", " << p.x[i].y << ", " << p.x[i].z
    << "] m)";
  return s.str();
}

// Excessive overlap: the deepest particle-particle, particle-plane or particle-mesh overlap, into
// status->particle and msg.
void DescribeOverlap(const Workspace& m, const Particles& p, const SystemConfig& config,
                     double time, StepStatus* status, std::ostringstream& msg) {
  double worst = 0;
  int64_t id = -1;
  std::string against;
  for (size_t i = 0; i + 1 < m.list.start.size(); ++i)
    for (int32_t k = m.list.start[i]; k < m.list.start[i + 1]; ++k) {
      const int32_t j = m.list.partner[k];
      const double ov = (p.radius[i] + p.radius[j] - Norm(p.x[j] - p.x[i])) /
                        (2.0 * std::min(p.radius[i], p.radius[j]));
      if (ov > worst) {
        worst = ov;
        const size_t a = p.id[i] < p.id[j] ? i : j, b = a == i ? j : i;
        id = p.id[a];
        against =
            " " + Where(p, a) + " against particle " + std::to_string(p.id[b]) + " " + Where(p, b);
      }
    }
  for (size_t e = 0; e < m.wall_i.size(); ++e) {
    const int32_t i = m.wall_i[e];
    const Plane& pl = config.planes[m.wall_k[e]];
    const double ov = (p.radius[i] - Dot(p.x[i] - pl.point, pl.normal)) / (2 * p.radius[i]);
    if (ov > worst) {
      worst = ov;
      id = p.id[i];
      against = " " + Where(p, i) + " against wall plane " + std::to_string(m.wall_k[e]);
    }
  }
  if (m.mesh_worst > worst && m.mesh_worst_id >= 0) {
    worst = m.mesh_worst;
    id = m.mesh_worst_id;
    const std::string& name = m.meshes[m.mesh_worst_mesh].mesh.name;
    against = " against mesh '" + (name.empty() ? std::to_string(m.mesh_worst_mesh) : name) +
              "' (a particle pinched by a moving mesh: keep walls a few diameters away from "
              "its path, or lower its speed)";
  }
  status->particle = id;
  msg << "particle " << id << " overlaps by " << 100.0 * worst << "% of its diameter" << against
      << " at t = " << time << " s (limit " << 100.0 * config.max_overlap_fraction
      << "%); lower time_step.rayleigh_fraction or raise the shear modulus";
}

// Rare path: finds the offending particle with the smallest persistent id and says what to do.
void Diagnose(const Workspace& m, const Particles& p, const SystemConfig& config, double time,
              StepStatus* status) {
  status->time = time;
  std::ostringstream msg;
  msg.precision(6);
  if (status->flags & kNonFinite) {
    const int64_t id = FirstById(p, [&](size_t i) {
                         return !(IsFinite(p.x[i]) && IsFinite(p.v[i]) && IsFinite(p.w[i]));
                       }).first;
    status->particle = id;
    msg << "particle " << id << " has a non-finite position or velocity at t = " << time
        << " s; lower time_step.rayleigh_fraction";
  } else if (status->flags & kRunawaySpeed) {
    const double vmax2 = config.max_speed * config.max_speed;
    auto [id, i] = FirstById(p, [&](size_t i) { return Norm2(p.v[i]) > vmax2; });
    status->particle = id;
    msg << "particle " << id << " moves at " << Norm(p.v[i]) << " m/s at t = " << time
        << " s, above the runaway limit " << config.max_speed
        << " m/s; lower time_step.rayleigh_fraction or check restitution <= 1";
  } else {
    DescribeOverlap(m, p, config, time, status, msg);
  }
  status->message = msg.str();
}

}  // namespace

StepStatus CheckHealth(const Workspace& m, const Particles& p, const SystemConfig& config,
                       double time, bool finite, double max_v2) {
  StepStatus status;
  if (!finite) status.flags |= kNonFinite;
  if (max_v2 > config.max_speed * config.max_speed) status.flags |= kRunawaySpeed;
  if (m.max_overlap > config.max_overlap_fraction) status.flags |= kExcessiveOverlap;
  if (!status.ok()) Diagnose(m, p, config, time, &status);
  return status;
}

}  // namespace dem::internal
