// Rigid clumps: bodies made of overlapping spheres (multi-sphere particles, as EDEM and LIGGGHTS'
// multisphere model use for non-spherical grains; the study's ice fragments are tetrahedral
// clumps, paper section 4, Fig. 7, Table 3). Public header of the dem module.
//
// A clump's spheres are ordinary particles of the System (they have persistent ids, take part in
// every contact, sleep and are saved like any sphere), with three differences:
//   - no contact between two spheres of the same clump (the neighbour list skips those pairs);
//   - they are not integrated on their own: after the force pass their forces and torques are
//     summed onto the clump (force, and torque about its centre of mass), the clump is integrated
//     as a rigid body, and each sphere is placed at x + R r_k with velocity v + w x R r_k and
//     angular velocity w, so contact damping and tangential history see the rigid motion;
//   - their `mass` and `inv_mass` are the clump's (the mass a contact law uses for its damping,
//     as LIGGGHTS' granular pair styles take the rigid body's mass), and `inv_inertia` is the
//     inverse of the clump's smallest principal moment (it only caps the rolling torque).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "dem/mesh.h"
#include "dem/transform.h"
#include "dem/vec3.h"

namespace dem {

struct Particles;

// A clump template: spheres in the template's own frame.
struct ClumpTemplate {
  std::string name;
  std::vector<Vec3> centers;  // sphere centres in the template frame [m] (S)
  std::vector<double> radii;  // sphere radii [m] (S)
};

// The study's four approximations of a regular tetrahedron of side 10 mm (paper section 4,
// Fig. 7, Table 3), centroid at the origin, vertices along (+-1, +-1, +-1) (an even number of
// minus signs). The paper gives the sphere diameters, not their places; every sphere here is
// inscribed in the tetrahedron:
//   tetra1:  one sphere of diameter 4 mm at the centroid (the insphere has 4.08 mm);
//   tetra4:  four of 3.5 mm, each tangent to the three faces of one corner (centre at 3 r from
//            the vertex: 0.874 mm from the centroid);
//   tetra8:  tetra4 + four of 1.75 mm, likewise in the corners (3.499 mm from the centroid);
//   tetra12: tetra8 + four of 0.875 mm, likewise (4.811 mm from the centroid).
// With halving diameters each corner sphere touches the next one exactly (their centres lie
// 3 (r1 - r2) = r1 + r2 apart), which is what the study's sizes suggest.
const std::vector<ClumpTemplate>& TetrahedronTemplates();
// The built-in template of that name (tetra1, tetra4, tetra8, tetra12), or nullptr.
const ClumpTemplate* FindBuiltinTemplate(const std::string& name);

// Default resolution of ClumpMassProperties: columns across the larger of the x and y extents.
constexpr int kClumpMassCells = 400;

// Volume, mass, centre of mass and inertia tensor (about the CoM, template axes; the convention
// of dem::MassProperties) of the union of the template's spheres at `density`: a region covered
// by several spheres counts once. Integrated numerically: square columns of side h along z (x, y
// at the column centre), the union of the spheres' chords in each column found exactly (sorted,
// merged intervals) and integrated in z in closed form; x^2 and y^2 get the in-column h^2 / 12.
// Accuracy, checked against closed forms (tests/dem/clump_test.cpp): volume and inertia of a
// sphere, and of two overlapping spheres (spherical caps), within 1e-4 relative at the default
// resolution. Throws std::invalid_argument for an empty template, centres and radii of different
// lengths, a radius not > 0 or a density not > 0.
MassProperties ClumpMassProperties(const ClumpTemplate& t, double density,
                                   int cells = kClumpMassCells);

// Principal axes of a symmetric 3x3 tensor (cyclic Jacobi): moments in ascending order and the
// rotation whose columns are the axes (principal frame -> the tensor's frame, right handed).
struct PrincipalAxes {
  Vec3 moments;
  Quat rotation;
};
PrincipalAxes ComputePrincipalAxes(const std::array<std::array<double, 3>, 3>& tensor);

// A template prepared for simulation: its mass properties per unit density and its spheres in
// the principal frame (origin at the centre of mass).
// Largest (max - min) / max of the principal moments of a shape taken for a spherical top.
constexpr double kSphericalTopSpread = 1e-4;

struct ClumpShape {
  ClumpTemplate source;
  double volume = 0;           // of the union of the spheres [m^3]
  Vec3 center_of_mass;         // template frame [m]
  Vec3 moments_per_density;    // principal moments of inertia / density [m^5]
  Quat principal;              // principal frame -> template frame
  std::vector<Vec3> offsets;   // sphere centres - CoM, principal frame [m] (S)
  std::vector<double> radii;   // [m] (S)
  double bounding_radius = 0;  // max |offset| + r: a sphere about the CoM holding the clump [m]
  double min_radius = 0;       // smallest sphere [m]
  // The three principal moments equal to kSphericalTopSpread relative (a regular tetrahedron of
  // equal spheres; one sphere): they are set to their mean, and the torque-free rotation is one
  // turn about the body-fixed L (ClumpSet::BeginStep).
  bool spherical_top = false;
  size_t size() const { return radii.size(); }
};
ClumpShape MakeClumpShape(const ClumpTemplate& t);

// State of the clumps of a System, one entry per clump, one array per field (C clumps).
// The body frame of a clump is its principal frame: origin at the CoM, axes the principal axes.
struct Clumps {
  std::vector<int32_t> shape;     // index of its ClumpShape in the System (C)
  std::vector<int32_t> material;  // index into the MaterialTable (C)
  std::vector<double> mass;       // [kg] (C)
  std::vector<Vec3> inertia;      // principal moments [kg m^2] (C)
  std::vector<Vec3> x;            // centre of mass [m] (C)
  std::vector<Vec3> v;            // velocity of the centre of mass [m/s] (C)
  std::vector<Quat> q;            // orientation: principal frame -> world (C)
  std::vector<Vec3> l;            // angular momentum in the principal frame [kg m^2/s] (C)
  std::vector<Vec3> f;            // force of the last step, gravity included [N] (C)
  std::vector<Vec3> t;            // torque of the last step about the CoM, world [N m] (C)
  std::vector<uint8_t> asleep;    // 1 while the clump (all its spheres) sleeps (C)
  std::vector<int32_t> first;     // its spheres are member[first[c] .. first[c + 1]] (C + 1)
  std::vector<int64_t> member;    // persistent ids of the spheres, in template order
  size_t size() const { return shape.size(); }
  // Angular velocity in world [rad/s]: R (L / I).
  Vec3 AngularVelocity(size_t c) const;
  // World position of sphere k of clump c: x + R offset_k.
  Vec3 MemberPosition(size_t c, const ClumpShape& s, size_t k) const;
};

// The clumps of a System and the bookkeeping that ties their spheres (persistent ids) to storage
// indices. Internal to dem: System owns one and calls its step hooks (dem/system.cpp).
class ClumpSet {
 public:
  bool empty() const { return state_.size() == 0; }
  int AddShape(const ClumpTemplate& t);  // an identical template already added is reused
  const std::vector<ClumpShape>& shapes() const { return shapes_; }
  const Clumps& state() const { return state_; }
  Clumps& mutable_state() { return state_; }

  // Registers a clump whose spheres were just added to `p` (ids members[0..S)); returns its index.
  int64_t Add(int shape, int material, double density, const Vec3& com, const Quat& q,
              const Vec3& v, const Vec3& w, const Vec3& gravity,
              const std::vector<int64_t>& members, Particles& p);
  // Clump index of persistent id `id`, or -1 for a single sphere.
  int32_t ClumpOf(int64_t id) const {
    return id >= 0 && id < static_cast<int64_t>(clump_of_id_.size()) ? clump_of_id_[id] : -1;
  }
  // Every id of `ids` plus all spheres of the clumps they belong to; those clumps are dropped.
  std::vector<int64_t> RemoveClumpsOf(const std::vector<int64_t>& ids);
  // Refreshes the storage index of every sphere after storage changed; returns the clump of each
  // storage index (-1 for single spheres), or nullptr when there are no clumps.
  const int32_t* Reindex(const Particles& p, int64_t next_id);
  // The clump of each storage index as the last Reindex made it, or nullptr when there are no
  // clumps or storage has grown since (spheres appended by System::AddParticle).
  const int32_t* clump_of_index(size_t n) const {
    return !empty() && clump_of_index_.size() == n ? clump_of_index_.data() : nullptr;
  }

  // Step hooks (velocity Verlet for the centre of mass; for the rotation the symplectic splitting
  // of Dullweber, Leimkuhler & McLachlan 1997, J. Chem. Phys. 107:5840, the scheme of LAMMPS'
  // and LIGGGHTS' NO_SQUISH rigid integrators: half kick of L, free rotation as the exact flows
  // about axes 1, 2, 3, 2, 1, half kick). Each clump touches only its own spheres, so the
  // parallel loops are race-free and their results do not depend on the thread count.
  struct BeginReport {
    bool woke = false;  // spheres of a waking clump were set awake: refresh the awake lists
    double max_member_speed2 = 0;  // largest (sphere displacement / dt)^2 of this step [m^2/s^2]
  };
  // After the spheres' own first half kick and drift: wakes a sleeping clump that has an awake
  // sphere (all its spheres, at rest), then half kick + drift of every awake clump and placement
  // of its spheres (force and torque zeroed for the coming force pass).
  // `moved` (one flag per particle, or null): set for the spheres of each clump it wakes, which
  // move from this step on (Workspace::moved, for the neighbour list's partial build).
  // `inv_spin` (one per particle, or null): 1/|w| of each sphere it places (Workspace::inv_spin).
  // `awake` (or null): the storage index of every awake sphere, in any order (Workspace::active,
  // made since the last change of an awake flag): a waking clump is found from these alone
  // instead of from every sphere, a serial pass over all of storage each step.
  BeginReport BeginStep(Particles& p, double dt, int threads, uint8_t* moved = nullptr,
                        double* inv_spin = nullptr, const std::vector<int32_t>* awake = nullptr);
  // After the force pass: sums each awake clump's sphere forces (+ m g) and torques about its CoM
  // (in template order), second half kick, sphere velocities. Returns false on a non-finite state.
  bool EndStep(Particles& p, const Vec3& gravity, double dt, int threads);
  // After a sleep check (dem/system.cpp UpdateSleep): the spheres of an awake clump share one
  // quiet count (the smallest: a sphere put to sleep counts as quiet_checks + 2), so the clump
  // sleeps as a unit once every sphere has been quiet for quiet_checks checks outside the mesh
  // zones. Returns whether any awake flag changed.
  bool SyncSleep(Particles& p, int quiet_checks);

  // Totals over the clumps, in clump order.
  double KineticEnergy() const;  // translational + rotational [J]
  double PotentialEnergy(const Vec3& gravity) const;
  Vec3 Momentum() const;

  // Lists the clumps' state and indices to `archive` (dem/archive.h; System::SaveState). The
  // shapes are not among them: they are added again from their templates.
  template <typename Archive>
  void Fields(Archive& archive) {
    Clumps& c = state_;
    for (auto* v : {&c.shape, &c.material}) archive(*v);
    archive(c.mass);
    for (auto* v : {&c.inertia, &c.x, &c.v, &c.l, &c.f, &c.t}) archive(*v);
    archive(c.q);
    archive(c.asleep);
    archive(c.first);
    archive(c.member);
    archive(index_);
    archive(clump_of_id_);
    archive(clump_of_index_);
  }

 private:
  void Place(size_t c, Particles& p, bool positions) const;  // spheres' x (optional), v, w

  std::vector<ClumpShape> shapes_;
  Clumps state_;
  std::vector<int32_t> index_;        // storage index of each member (member.size())
  std::vector<int32_t> clump_of_id_;  // clump of each persistent id, -1 for single spheres
  std::vector<int32_t> clump_of_index_;
  std::vector<uint8_t> waking_;  // BeginStep's scratch: the sleeping clumps it wakes
};

}  // namespace dem
