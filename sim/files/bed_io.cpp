#include "sim/files/bed_io.h"

#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "sim/files/h5_output.h"
#include "sim/files/internal_h5.h"
#include "sim/input/scene.h"

namespace sim {
namespace {

using h5::CheckId;
using h5::CheckOk;
using h5::Handle;

// The bonds' datasets of a bed file (/bonds/NAME), scalars then vectors (see bed_io.h).
constexpr const char* kBondScalars[9] = {"radius",           "kn",       "ks",
                                         "tensile_strength", "cohesion", "tan_friction",
                                         "damping_ratio",    "fn",       "mt"};
constexpr const char* kBondVectors[3] = {"fs", "mb", "normal"};

// A new group of a bed file and the two id columns a, b (n) that /contacts and /bonds open with.
Handle NewGroupWithPairs(hid_t file, const std::string& name, const int64_t* a, const int64_t* b,
                         size_t n) {
  Handle group(CheckId(H5Gcreate2(file, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                       ("H5Gcreate2 " + name).c_str()),
               H5Gclose);
  h5::WriteArray(group.get(), "a", H5T_STD_I64LE, H5T_NATIVE_INT64, a, n, 1);
  h5::WriteArray(group.get(), "b", H5T_STD_I64LE, H5T_NATIVE_INT64, b, n, 1);
  return group;
}

// The particle datasets of /particles that are hard links to the snapshot's (one copy on disk).
const char* const kLinkedFields[] = {"id",     "position", "velocity", "angular_velocity",
                                     "radius", "material"};

// The last step's force or torque (N) for the file, zero where `flag` (N) is `asleep_value`. A
// sleeper's force is not kept while it sleeps (awake neighbours add to it and nothing clears
// it), and a bed loads all awake: it must start as a waking body does, at rest in equilibrium
// with zero force (dem::internal::WakeAll, ClumpSet::BeginStep), not kick on a stale sum.
template <typename Flag>
std::vector<dem::Vec3> AwakeOnly(const std::vector<dem::Vec3>& field, const std::vector<Flag>& flag,
                                 int asleep_value) {
  std::vector<dem::Vec3> out = field;
  for (size_t i = 0; i < out.size() && i < flag.size(); ++i)
    if (flag[i] == asleep_value) out[i] = dem::Vec3{};
  return out;
}

void WriteVectors(hid_t group, const char* name, const std::vector<dem::Vec3>& field,
                  const std::vector<size_t>& order) {
  std::vector<double> buffer(3 * order.size());
  for (size_t k = 0; k < order.size(); ++k) {
    const dem::Vec3& a = field[order[k]];
    buffer[3 * k + 0] = a.x;
    buffer[3 * k + 1] = a.y;
    buffer[3 * k + 2] = a.z;
  }
  h5::WriteArray(group, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, buffer.data(), order.size(), 3);
}

// Writes (C x 3) rows of a per-clump field.
void WriteClumpVectors(hid_t group, const char* name, const std::vector<dem::Vec3>& field) {
  std::vector<double> buffer;
  for (const dem::Vec3& a : field) buffer.insert(buffer.end(), {a.x, a.y, a.z});
  h5::WriteArray(group, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, buffer.data(), field.size(), 3);
}

void WriteStringList(hid_t location, const std::string& name,
                     const std::vector<std::string>& strings) {
  Handle type(CheckId(H5Tcopy(H5T_C_S1), "H5Tcopy"), H5Tclose);
  CheckOk(H5Tset_size(type.get(), H5T_VARIABLE), "H5Tset_size");
  CheckOk(H5Tset_cset(type.get(), H5T_CSET_UTF8), "H5Tset_cset");
  const hsize_t n = strings.size();
  Handle space(CheckId(H5Screate_simple(1, &n, nullptr), "H5Screate_simple"), H5Sclose);
  Handle lcpl(CheckId(H5Pcreate(H5P_LINK_CREATE), "H5Pcreate"), H5Pclose);
  CheckOk(H5Pset_create_intermediate_group(lcpl.get(), 1), "H5Pset_create_intermediate_group");
  Handle dataset(CheckId(H5Dcreate2(location, name.c_str(), type.get(), space.get(), lcpl.get(),
                                    H5P_DEFAULT, H5P_DEFAULT),
                         "H5Dcreate2 " + name),
                 H5Dclose);
  std::vector<const char*> pointers;
  for (const std::string& s : strings) pointers.push_back(s.c_str());
  if (n > 0) {
    CheckOk(H5Dwrite(dataset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, pointers.data()),
            "H5Dwrite " + name);
  }
}

// The clump templates and the clumps' state (see bed_io.h).
void WriteClumps(hid_t file, const dem::System& system) {
  std::vector<std::string> names;
  std::vector<int32_t> counts;
  std::vector<double> spheres;
  for (int k = 0; k < system.num_clump_templates(); ++k) {
    const dem::ClumpTemplate& t = system.clump_shape(k).source;
    names.push_back(t.name);
    counts.push_back(static_cast<int32_t>(t.radii.size()));
    for (size_t s = 0; s < t.radii.size(); ++s)
      spheres.insert(spheres.end(), {t.centers[s].x, t.centers[s].y, t.centers[s].z, t.radii[s]});
  }
  WriteStringList(file, "/clump_templates/names", names);
  Handle templates(CheckId(H5Gopen2(file, "/clump_templates", H5P_DEFAULT), "H5Gopen2"), H5Gclose);
  h5::WriteArray(templates.get(), "sphere_count", H5T_STD_I32LE, H5T_NATIVE_INT32, counts.data(),
                 counts.size(), 1);
  h5::WriteArray(templates.get(), "spheres", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, spheres.data(),
                 spheres.size() / 4, 4);

  const dem::Clumps& c = system.clumps();
  Handle group(CheckId(H5Gcreate2(file, "/clumps", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                       "H5Gcreate2 /clumps"),
               H5Gclose);
  const size_t n = c.size();
  h5::WriteArray(group.get(), "template", H5T_STD_I32LE, H5T_NATIVE_INT32, c.shape.data(), n, 1);
  h5::WriteArray(group.get(), "material", H5T_STD_I32LE, H5T_NATIVE_INT32, c.material.data(), n, 1);
  WriteClumpVectors(group.get(), "position", c.x);
  std::vector<double> q;
  for (const dem::Quat& o : c.q) q.insert(q.end(), {o.w, o.x, o.y, o.z});
  h5::WriteArray(group.get(), "orientation", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, q.data(), n, 4);
  h5::MarkQuaternions(group.get(), "orientation", false);
  WriteClumpVectors(group.get(), "velocity", c.v);
  std::vector<dem::Vec3> w(n);
  for (size_t k = 0; k < n; ++k) w[k] = c.AngularVelocity(k);
  WriteClumpVectors(group.get(), "angular_velocity", w);
  WriteClumpVectors(group.get(), "angular_momentum", c.l);
  WriteClumpVectors(group.get(), "force", AwakeOnly(c.f, c.asleep, 1));
  WriteClumpVectors(group.get(), "torque", AwakeOnly(c.t, c.asleep, 1));
  h5::WriteArray(group.get(), "member", H5T_STD_I64LE, H5T_NATIVE_INT64, c.member.data(),
                 c.member.size(), 1);
}

// Writes everything but the sidecar into the new file `file`.
// The bonds, intact and broken, with their state (see bed_io.h), in the system's order.
void WriteBonds(hid_t file, const std::vector<dem::Bond>& bonds) {
  const size_t n = bonds.size();
  std::vector<int64_t> a(n), b(n);
  std::vector<uint8_t> intact(n);
  // Scalars, one column each: radius, kn, ks, tensile_strength, cohesion, tan_friction,
  // damping_ratio, fn, mt.
  std::vector<double> scalar(9 * n);
  std::vector<double> vectors(9 * n);  // fs, mb, normal (3 columns each)
  for (size_t k = 0; k < n; ++k) {
    const dem::Bond& d = bonds[k];
    a[k] = d.a;
    b[k] = d.b;
    intact[k] = d.intact ? 1 : 0;
    const double s[9] = {d.radius,           d.kn,       d.ks,
                         d.tensile_strength, d.cohesion, d.tan_friction,
                         d.damping_ratio,    d.fn,       d.mt};
    for (int j = 0; j < 9; ++j) scalar[j * n + k] = s[j];
    const dem::Vec3 v[3] = {d.fs, d.mb, d.normal};
    for (int j = 0; j < 3; ++j) {
      vectors[j * 3 * n + 3 * k + 0] = v[j].x;
      vectors[j * 3 * n + 3 * k + 1] = v[j].y;
      vectors[j * 3 * n + 3 * k + 2] = v[j].z;
    }
  }
  const Handle group = NewGroupWithPairs(file, "/bonds", a.data(), b.data(), n);
  h5::WriteArray(group.get(), "intact", H5T_STD_U8LE, H5T_NATIVE_UINT8, intact.data(), n, 1);
  for (int j = 0; j < 9; ++j)
    h5::WriteArray(group.get(), kBondScalars[j], H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                   scalar.data() + j * n, n, 1);
  for (int j = 0; j < 3; ++j)
    h5::WriteArray(group.get(), kBondVectors[j], H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                   vectors.data() + j * 3 * n, n, 3);
}

h5::SnapshotEntry WriteBed(hid_t file, const dem::System& system, const std::string& scene_yaml,
                           const PourPoint* pour) {
  const dem::Particles& p = system.particles();
  Handle root(CheckId(H5Gopen2(file, "/", H5P_DEFAULT), "H5Gopen2 /"), H5Gclose);
  h5::WriteStringAttribute(root.get(), "version", SCOOPSIM_VERSION);
  h5::WriteStringAttribute(root.get(), "scene_yaml", scene_yaml);
  h5::WriteDoubleAttribute(root.get(), "time", system.time());
  h5::WriteStateHash(root.get(), system.StateHash());
  if (pour != nullptr) {
    h5::WriteDoubleAttribute(root.get(), "pour_layers", pour->layers);
    h5::WriteDoubleAttribute(root.get(), "pour_poured", static_cast<double>(pour->poured));
    h5::WriteU64Attribute(root.get(), "pour_rng", pour->rng);
    h5::WriteDoubleAttribute(root.get(), "pour_layer_t0", pour->layer_t0);
    h5::WriteDoubleAttribute(root.get(), "pour_layer_fall", pour->layer_fall);
    h5::WriteDoubleAttribute(root.get(), "pour_layer_settled", pour->settled ? 1.0 : 0.0);
    h5::WriteBytes(file, "/pour_state", system.SaveState());
  }

  // Particles: the snapshot holds the arrays; /particles links to them and adds force, torque.
  const h5::SnapshotEntry entry = h5::WriteParticleSnapshot(file, 0, system.time(), p);
  Handle particles(CheckId(H5Gcreate2(file, "/particles", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                           "H5Gcreate2 /particles"),
                   H5Gclose);
  for (const char* field : kLinkedFields) {
    const std::string target = entry.group + "/" + field;
    CheckOk(H5Lcreate_hard(file, target.c_str(), particles.get(), field, H5P_DEFAULT, H5P_DEFAULT),
            "H5Lcreate_hard " + target);
  }
  const std::vector<size_t> order = h5::IdOrder(p);
  WriteVectors(particles.get(), "force", AwakeOnly(p.f, p.awake, 0), order);
  WriteVectors(particles.get(), "torque", AwakeOnly(p.t, p.awake, 0), order);

  std::vector<std::string> names;
  for (int i = 0; i < system.materials().size(); ++i) names.push_back(system.materials()[i].name);
  WriteStringList(file, "/materials/names", names);

  // Contact history, already sorted by (a, b).
  const std::vector<dem::ContactRecord> contacts = system.Contacts();
  const size_t m = contacts.size();
  std::vector<int64_t> a(m), b(m);
  std::vector<double> shear(3 * m);
  for (size_t k = 0; k < m; ++k) {
    a[k] = contacts[k].a;
    b[k] = contacts[k].b;
    shear[3 * k + 0] = contacts[k].shear.x;
    shear[3 * k + 1] = contacts[k].shear.y;
    shear[3 * k + 2] = contacts[k].shear.z;
  }
  Handle group = NewGroupWithPairs(file, "/contacts", a.data(), b.data(), m);
  h5::WriteArray(group.get(), "shear", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, shear.data(), m, 3);
  group.reset();
  if (system.clumps().size() > 0) WriteClumps(file, system);
  if (!system.bonds().empty()) WriteBonds(file, system.bonds());

  return entry;
}

// A number or a point with 6 significant digits, for messages.
std::string Num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", v);
  return buffer;
}
std::string Num(const dem::Vec3& v) {
  return "[" + Num(v.x) + ", " + Num(v.y) + ", " + Num(v.z) + "]";
}

// Fails on the first row of a (rows x 3) dataset that is not finite.
void CheckFinite(const h5::Reader& in, const std::string& name,
                 const std::vector<dem::Vec3>& rows) {
  for (size_t k = 0; k < rows.size(); ++k) {
    if (!dem::IsFinite(rows[k]))
      in.Fail(name, "row " + std::to_string(k) + ": expected finite values, got " + Num(rows[k]));
  }
}

// A bed file's particles: ids (ascending, unique), centres, radii, material indices into names.
struct BedParticles {
  std::vector<int64_t> ids;
  std::vector<dem::Vec3> x;
  std::vector<double> radius;
  std::vector<int32_t> material;
  std::vector<std::string> names;
};

// The bonds of a bed file, their ids mapped by `new_id` (saved id -> id in the system; -1:
// not in the bed), checked: ids in the bed, no NaN, strengths > 0 (+inf allowed).
std::vector<dem::Bond> ReadBonds(const h5::Reader& in,
                                 const std::function<int64_t(int64_t)>& new_id) {
  std::vector<dem::Bond> bonds;
  if (!in.Exists("/bonds")) return bonds;
  int64_t n = 0;
  const std::vector<int64_t> a =
      in.Read<int64_t>("/bonds/a", H5T_INTEGER, H5T_NATIVE_INT64, -1, 1, &n);
  const std::vector<int64_t> b = in.Read<int64_t>("/bonds/b", H5T_INTEGER, H5T_NATIVE_INT64, n, 1);
  const std::vector<uint8_t> intact =
      in.Read<uint8_t>("/bonds/intact", H5T_INTEGER, H5T_NATIVE_UINT8, n, 1);
  std::vector<std::vector<double>> scalar(9);
  for (int j = 0; j < 9; ++j) {
    const std::string name = std::string("/bonds/") + kBondScalars[j];
    scalar[j] = in.Read<double>(name, H5T_FLOAT, H5T_NATIVE_DOUBLE, n, 1);
    for (int64_t k = 0; k < n; ++k) {
      const double v = scalar[j][k];
      // Strengths (columns 3, 4) may be +inf (never breaks); nothing may be NaN or -inf.
      const bool ok = j == 3 || j == 4 ? v > 0 : std::isfinite(v);
      if (!ok) in.Fail(name, "bond " + std::to_string(k) + ": " + Num(v));
    }
  }
  std::vector<std::vector<dem::Vec3>> vectors(3);
  for (int j = 0; j < 3; ++j) {
    const std::string name = std::string("/bonds/") + kBondVectors[j];
    vectors[j] = in.ReadVectors(name, n);
    CheckFinite(in, name, vectors[j]);
  }
  bonds.resize(static_cast<size_t>(n));
  for (int64_t k = 0; k < n; ++k) {
    dem::Bond& d = bonds[k];
    d.a = new_id(a[k]);
    d.b = new_id(b[k]);
    if (d.a < 0 || d.b < 0) {
      in.Fail(d.a < 0 ? "/bonds/a" : "/bonds/b", "bond " + std::to_string(k) + ": particle " +
                                                     std::to_string(d.a < 0 ? a[k] : b[k]) +
                                                     " is not in the bed");
    }
    d.intact = intact[k] != 0;
    double* fields[9] = {&d.radius,           &d.kn,       &d.ks,
                         &d.tensile_strength, &d.cohesion, &d.tan_friction,
                         &d.damping_ratio,    &d.fn,       &d.mt};
    for (int j = 0; j < 9; ++j) *fields[j] = scalar[j][k];
    d.fs = vectors[0][k];
    d.mb = vectors[1][k];
    d.normal = vectors[2][k];
  }
  return bonds;
}

// Reads and checks the particles' ids, centres, radii and materials: ids ascending, radii > 0,
// centres finite and inside the box [lo, hi] (the floor and side walls hold every particle of a
// bed, so a centre outside them is a corrupt or foreign file; the top is open: a particle the
// scoop flung may be above it, by up to the box's height), material indices into the names.
BedParticles ReadParticles(const h5::Reader& in, const dem::Vec3& lo, const dem::Vec3& hi) {
  BedParticles bed;
  int64_t n = 0;
  bed.ids = in.Read<int64_t>("/particles/id", H5T_INTEGER, H5T_NATIVE_INT64, -1, 1, &n);
  bed.x = in.ReadVectors("/particles/position", n);
  bed.radius = in.Read<double>("/particles/radius", H5T_FLOAT, H5T_NATIVE_DOUBLE, n, 1);
  bed.material = in.Read<int32_t>("/particles/material", H5T_INTEGER, H5T_NATIVE_INT32, n, 1);
  bed.names = in.ReadStrings("/materials/names");
  const std::vector<int64_t>& ids = bed.ids;
  for (int64_t k = 1; k < n; ++k) {
    if (ids[k] <= ids[k - 1]) in.Fail("/particles/id", "ids must be unique and ascending");
  }
  for (int64_t k = 0; k < n; ++k) {
    const std::string particle = "particle " + std::to_string(ids[k]);
    if (!(bed.radius[k] > 0 && std::isfinite(bed.radius[k])))
      in.Fail("/particles/radius", particle + ": expected a radius > 0, got " + Num(bed.radius[k]));
    const dem::Vec3& c = bed.x[k];
    if (!dem::IsFinite(c))
      in.Fail("/particles/position", particle + ": expected a finite centre, got " + Num(c));
    if (!(c.x >= lo.x && c.x <= hi.x && c.y >= lo.y && c.y <= hi.y && c.z >= lo.z)) {
      in.Fail("/particles/position",
              particle + ": expected a centre inside the scene's box " + Num(lo) + " .. " +
                  Num(hi) + " m (above its floor, between its side walls), got " + Num(c));
    }
    // Open, but not without end: a centre more than the box's height above its top is no
    // particle a dig could have flung (one at 50 m made the scoop's approach start there and
    // take 345 s of simulated time).
    const double ceiling = hi.z + (hi.z - lo.z);
    if (!(c.z <= ceiling)) {
      in.Fail("/particles/position",
              particle + ": expected a centre at most the box's height above its open top (z <= " +
                  Num(ceiling) + " m), got " + Num(c));
    }
    const int32_t i = bed.material[k];
    if (i < 0 || static_cast<size_t>(i) >= bed.names.size()) {
      in.Fail("/particles/material", particle + ": material index " + std::to_string(i) +
                                         " not in /materials/names (" +
                                         std::to_string(bed.names.size()) + " names)");
    }
  }
  return bed;
}

// The clumps of a bed file (see bed_io.h), read and checked against its particles.
struct SavedClumps {
  std::vector<dem::ClumpTemplate> templates;
  std::vector<int32_t> shape, material;
  std::vector<dem::Vec3> x, v, w, l, f, t;
  std::vector<dem::Quat> q;
  std::vector<int64_t> member;
  std::vector<int64_t> first_slot;  // slot (in /particles) of each clump's first sphere
  std::vector<int32_t> at_slot;     // clump of each particle slot, -1 for a single sphere

  size_t size() const { return shape.size(); }
  size_t spheres(size_t c) const { return templates[shape[c]].radii.size(); }
};

SavedClumps ReadClumps(const h5::Reader& in, const std::vector<int64_t>& ids,
                       const std::vector<double>& radius, size_t num_materials) {
  SavedClumps s;
  if (!in.Exists("/clumps")) return s;
  const std::vector<std::string> names = in.ReadStrings("/clump_templates/names");
  const int64_t nt = static_cast<int64_t>(names.size());
  const std::vector<int32_t> counts =
      in.Read<int32_t>("/clump_templates/sphere_count", H5T_INTEGER, H5T_NATIVE_INT32, nt, 1);
  int64_t total = 0;
  for (int32_t k : counts) {
    if (k < 1) in.Fail("/clump_templates/sphere_count", "expected counts >= 1");
    total += k;
  }
  const std::vector<double> spheres =
      in.Read<double>("/clump_templates/spheres", H5T_FLOAT, H5T_NATIVE_DOUBLE, total, 4);
  size_t at = 0;
  for (int64_t k = 0; k < nt; ++k) {
    dem::ClumpTemplate t;
    t.name = names[k];
    for (int32_t e = 0; e < counts[k]; ++e, at += 4) {
      t.centers.push_back({spheres[at], spheres[at + 1], spheres[at + 2]});
      t.radii.push_back(spheres[at + 3]);
      if (!(t.radii.back() > 0) || !dem::IsFinite(t.centers.back()))
        in.Fail("/clump_templates/spheres", "template '" + t.name + "': a radius not > 0");
    }
    s.templates.push_back(t);
  }
  int64_t n = 0;
  s.shape = in.Read<int32_t>("/clumps/template", H5T_INTEGER, H5T_NATIVE_INT32, -1, 1, &n);
  s.material = in.Read<int32_t>("/clumps/material", H5T_INTEGER, H5T_NATIVE_INT32, n, 1);
  s.x = in.ReadVectors("/clumps/position", n);
  s.v = in.ReadVectors("/clumps/velocity", n);
  s.w = in.ReadVectors("/clumps/angular_velocity", n);
  s.l = in.ReadVectors("/clumps/angular_momentum", n);
  s.f = in.ReadVectors("/clumps/force", n);
  s.t = in.ReadVectors("/clumps/torque", n);
  const std::pair<const char*, const std::vector<dem::Vec3>*> fields[] = {
      {"/clumps/position", &s.x},
      {"/clumps/velocity", &s.v},
      {"/clumps/angular_velocity", &s.w},
      {"/clumps/angular_momentum", &s.l},
      {"/clumps/force", &s.f},
      {"/clumps/torque", &s.t}};
  for (const auto& [name, field] : fields) CheckFinite(in, name, *field);
  const std::vector<double> q =
      in.Read<double>("/clumps/orientation", H5T_FLOAT, H5T_NATIVE_DOUBLE, n, 4);
  for (int64_t c = 0; c < n; ++c) {
    const dem::Quat o{q[4 * c], q[4 * c + 1], q[4 * c + 2], q[4 * c + 3]};
    const double norm2 = o.w * o.w + o.x * o.x + o.y * o.y + o.z * o.z;
    if (!(std::abs(norm2 - 1.0) < 1e-9))
      in.Fail("/clumps/orientation", "clump " + std::to_string(c) + ": not a unit quaternion");
    s.q.push_back(o);
    if (s.shape[c] < 0 || s.shape[c] >= nt)
      in.Fail("/clumps/template", "clump " + std::to_string(c) + ": template index " +
                                      std::to_string(s.shape[c]) + " not in /clump_templates");
    if (s.material[c] < 0 || static_cast<size_t>(s.material[c]) >= num_materials)
      in.Fail("/clumps/material", "clump " + std::to_string(c) + ": material index " +
                                      std::to_string(s.material[c]) + " not in /materials/names");
  }
  int64_t members = 0;
  for (int64_t c = 0; c < n; ++c) members += static_cast<int64_t>(s.spheres(c));
  s.member = in.Read<int64_t>("/clumps/member", H5T_INTEGER, H5T_NATIVE_INT64, members, 1);
  // A clump's spheres are consecutive particles of the file with the template's radii.
  s.at_slot.assign(ids.size(), -1);
  size_t e = 0;
  for (int64_t c = 0; c < n; ++c) {
    const dem::ClumpTemplate& t = s.templates[s.shape[c]];
    const auto first = std::lower_bound(ids.begin(), ids.end(), s.member[e]);
    const int64_t slot = first - ids.begin();
    s.first_slot.push_back(slot);
    for (size_t k = 0; k < t.radii.size(); ++k, ++e) {
      const size_t at_k = static_cast<size_t>(slot) + k;
      if (at_k >= ids.size() || ids[at_k] != s.member[e] || s.at_slot[at_k] >= 0 ||
          radius[at_k] != t.radii[k]) {
        in.Fail("/clumps/member", "clump " + std::to_string(c) + ": sphere " +
                                      std::to_string(s.member[e]) +
                                      " is not the next particle of the bed with radius " +
                                      std::to_string(t.radii[k]) + " of template '" + t.name +
                                      "', or belongs to two clumps");
      }
      s.at_slot[at_k] = static_cast<int32_t>(c);
    }
  }
  return s;
}

}  // namespace

void SaveBed(const std::string& path, const dem::System& system, const std::string& scene_yaml,
             const PourPoint* pour) {
  namespace fs = std::filesystem;
  const std::string temporary = path + "." + std::to_string(::getpid()) + ".partial";
  h5::SnapshotEntry entry;
  try {
    Handle file = h5::CreateFile(temporary, /*swmr=*/false, nullptr, path);
    h5::WriteNewFile(file.get(), path,
                     [&] { entry = WriteBed(file.get(), system, scene_yaml, pour); });
    CheckOk(file.reset(), "H5Fclose " + temporary);
  } catch (const InputError& e) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw InputError(path + ": cannot save the bed: " + e.what());
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  }
  PlaceOutput(temporary, path);  // under the output lock (sim/files/h5_output.h)
  h5::WriteXdmf(path, {entry});
}

std::string BedSceneYaml(const std::string& path) {
  hid_t file_id = H5I_INVALID_HID;
  H5E_BEGIN_TRY { file_id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT); }
  H5E_END_TRY;
  if (file_id < 0) return "";
  Handle file(file_id, H5Fclose);
  htri_t exists = -1;
  H5E_BEGIN_TRY { exists = H5Aexists(file.get(), "scene_yaml"); }
  H5E_END_TRY;
  if (exists <= 0) return "";
  try {
    return h5::ReadStringAttribute(file.get(), "scene_yaml");
  } catch (const std::exception&) {
    return "";
  }
}

bool ReadPourPoint(const std::string& path, const std::string& scene_yaml, PourPoint* pour,
                   std::vector<char>* state) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec) || BedSceneYaml(path) != scene_yaml) return false;
  try {
    const Handle file = h5::OpenForReading(path, false);
    const h5::Reader in(path, file.get());
    if (!in.HasAttribute("/", "pour_rng")) return false;
    Handle attribute(CheckId(H5Aopen(file.get(), "pour_rng", H5P_DEFAULT), "H5Aopen pour_rng"),
                     H5Aclose);
    uint64_t rng = 0;
    CheckOk(H5Aread(attribute.get(), H5T_NATIVE_UINT64, &rng), "H5Aread pour_rng");
    // Counts held as doubles: out of range (a file not of ours) they are no keep to go on from
    // (and casting them would be undefined behaviour).
    const double layers = in.ReadDoubleAttribute("/", "pour_layers");
    const double poured = in.ReadDoubleAttribute("/", "pour_poured");
    if (!(layers >= 0 && layers <= 1e9 && poured >= 0 && poured <= 9e18)) return false;
    pour->layers = static_cast<int>(layers);
    pour->poured = static_cast<int64_t>(poured);
    pour->rng = rng;
    pour->layer_t0 = in.ReadDoubleAttribute("/", "pour_layer_t0");
    pour->layer_fall = in.ReadDoubleAttribute("/", "pour_layer_fall");
    pour->settled = in.HasAttribute("/", "pour_layer_settled") &&
                    in.ReadDoubleAttribute("/", "pour_layer_settled") != 0;
    pour->started = true;
    if (state != nullptr) {
      state->clear();
      if (in.Exists("/pour_state")) *state = in.ReadBytes("/pour_state");
    }
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

void LoadBed(const std::string& path, dem::System* system) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path + ": bed file not found");
  const Handle file = h5::OpenForReading(path, false);
  const h5::Reader in(path, file.get());

  // Read and check everything before touching the system.
  const dem::SystemConfig& config = system->config();
  const BedParticles bed = ReadParticles(in, config.domain_min, config.domain_max);
  const std::vector<int64_t>& ids = bed.ids;
  const std::vector<dem::Vec3>& x = bed.x;
  const std::vector<double>& radius = bed.radius;
  const std::vector<int32_t>& material = bed.material;
  const std::vector<std::string>& names = bed.names;
  const int64_t n = static_cast<int64_t>(ids.size());
  const std::vector<dem::Vec3> v = in.ReadVectors("/particles/velocity", n);
  const std::vector<dem::Vec3> w = in.ReadVectors("/particles/angular_velocity", n);
  const std::vector<dem::Vec3> force = in.ReadVectors("/particles/force", n);
  const std::vector<dem::Vec3> torque = in.ReadVectors("/particles/torque", n);
  int64_t m = 0;
  const std::vector<int64_t> a =
      in.Read<int64_t>("/contacts/a", H5T_INTEGER, H5T_NATIVE_INT64, -1, 1, &m);
  const std::vector<int64_t> b =
      in.Read<int64_t>("/contacts/b", H5T_INTEGER, H5T_NATIVE_INT64, m, 1);
  const std::vector<dem::Vec3> shear = in.ReadVectors("/contacts/shear", m);
  const double time = in.ReadDoubleAttribute("/", "time");
  const std::pair<const char*, const std::vector<dem::Vec3>*> fields[] = {
      {"/particles/velocity", &v},
      {"/particles/angular_velocity", &w},
      {"/particles/force", &force},
      {"/particles/torque", &torque},
      {"/contacts/shear", &shear}};
  for (const auto& [name, field] : fields) CheckFinite(in, name, *field);
  if (!std::isfinite(time)) in.Fail("time", "expected a finite time (s), got " + Num(time));
  // Optional: which particles sleep (a mid-run state, e.g. bench/dig_state.py's).
  std::vector<uint8_t> awake;
  if (in.Exists("/particles/awake"))
    awake = in.Read<uint8_t>("/particles/awake", H5T_INTEGER, H5T_NATIVE_UINT8, n, 1);
  const SavedClumps clumps = ReadClumps(in, ids, radius, names.size());

  // File material index -> system material index, by name; only materials in use must exist.
  std::vector<int> material_of(names.size(), -2);  // -2: not looked up yet
  for (int64_t k = 0; k < n; ++k) {
    const int32_t i = material[k];
    if (material_of[i] == -2) material_of[i] = system->materials().Find(names[i]);
    if (material_of[i] < 0) {
      in.Fail("/materials/names",
              "material '" + names[i] + "' of the bed is not among the scene's materials");
    }
  }
  // Saved id -> position in the file's (sorted) particle list, -1 if absent.
  auto slot_of = [&ids](int64_t id) -> int64_t {
    const auto it = std::lower_bound(ids.begin(), ids.end(), id);
    return it != ids.end() && *it == id ? it - ids.begin() : -1;
  };
  const int64_t num_planes = static_cast<int64_t>(system->config().planes.size());
  for (int64_t k = 0; k < m; ++k) {
    if (slot_of(a[k]) < 0) {
      in.Fail("/contacts/a", "contact " + std::to_string(k) + ": particle " + std::to_string(a[k]) +
                                 " is not in the bed");
    }
    if (b[k] >= 0 && slot_of(b[k]) < 0) {
      in.Fail("/contacts/b", "contact " + std::to_string(k) + ": particle " + std::to_string(b[k]) +
                                 " is not in the bed");
    }
    if (b[k] < 0 && -1 - b[k] >= num_planes) {
      in.Fail("/contacts/b", "contact " + std::to_string(k) + " touches plane " +
                                 std::to_string(-1 - b[k]) + ", but the scene has " +
                                 std::to_string(num_planes) + " planes");
    }
  }

  for (size_t c = 0; c < clumps.size(); ++c) {
    if (clumps.material[c] != material[clumps.first_slot[c]])
      in.Fail("/clumps/material", "clump " + std::to_string(c) + ": not its spheres' material");
  }

  // Particles, in saved id order: a bed loaded into an empty System keeps its ids. A clump is
  // added whole at its first sphere (its spheres have consecutive ids).
  system->Reserve(system->particles().size() + static_cast<size_t>(n));
  std::vector<int64_t> new_id(static_cast<size_t>(n));
  std::unordered_map<int64_t, size_t> slot_of_new_id;
  std::vector<int> shape_of(clumps.templates.size());
  for (size_t k = 0; k < clumps.templates.size(); ++k)
    shape_of[k] = system->AddClumpTemplate(clumps.templates[k]);
  for (int64_t k = 0; k < n; ++k) {
    const int32_t c = clumps.at_slot.empty() ? -1 : clumps.at_slot[k];
    if (c < 0) {
      new_id[k] = system->AddParticle(x[k], v[k], w[k], radius[k], material_of[material[k]]);
      slot_of_new_id.emplace(new_id[k], static_cast<size_t>(k));
      continue;
    }
    if (clumps.first_slot[c] != k) continue;  // added with its clump
    // The pose of the template frame from the saved principal frame, then the saved state as is.
    const int shape = shape_of[clumps.shape[c]];
    const dem::ClumpShape& cs = system->clump_shape(shape);
    dem::Pose pose;
    pose.orientation = clumps.q[c] * dem::Conjugate(cs.principal);
    pose.position = clumps.x[c] - dem::Rotate(pose.orientation, cs.center_of_mass);
    const int64_t index =
        system->AddClump(shape, pose, clumps.v[c], clumps.w[c], material_of[clumps.material[c]]);
    dem::Clumps& state = system->mutable_clumps();
    state.x[index] = clumps.x[c];
    state.v[index] = clumps.v[c];
    state.q[index] = clumps.q[c];
    state.l[index] = clumps.l[c];
    state.f[index] = clumps.f[c];
    state.t[index] = clumps.t[c];
    for (size_t e = 0; e < clumps.spheres(c); ++e) {
      new_id[k + e] = state.member[state.first[index] + e];
      slot_of_new_id.emplace(new_id[k + e], static_cast<size_t>(k + e));
    }
  }
  // The saved state of every sphere (a clump's as saved, not as recomputed from its pose) and
  // the last step's force and torque: velocity Verlet's first half kick uses them, so a
  // restored bed replays bit for bit.
  dem::Particles& p = system->mutable_particles();
  for (size_t i = 0; i < p.size(); ++i) {
    const auto it = slot_of_new_id.find(p.id[i]);
    if (it == slot_of_new_id.end()) continue;
    p.x[i] = x[it->second];
    p.v[i] = v[it->second];
    p.w[i] = w[it->second];
    p.f[i] = force[it->second];
    p.t[i] = torque[it->second];
    if (!awake.empty() && awake[it->second] == 0) {
      p.awake[i] = 0;  // asleep at rest, as dem::System puts a particle to sleep
      p.v[i] = dem::Vec3{};
      p.w[i] = dem::Vec3{};
    }
  }
  system->Touch();

  // Contact history, added to what the system already has.
  std::vector<dem::ContactRecord> records = system->Contacts();
  for (int64_t k = 0; k < m; ++k) {
    const int64_t new_b = b[k] >= 0 ? new_id[slot_of(b[k])] : b[k];
    records.push_back({new_id[slot_of(a[k])], new_b, shear[k]});
  }
  system->SetContacts(records);
  // Bonds (a bonded bed), with their state, intact or broken.
  const std::vector<dem::Bond> bonds = ReadBonds(in, [&](int64_t id) -> int64_t {
    const int64_t slot = slot_of(id);
    return slot < 0 ? -1 : new_id[slot];
  });
  if (!bonds.empty()) {
    try {
      system->AddBonds(bonds);
    } catch (const std::invalid_argument& e) {
      in.Fail("/bonds", e.what());
    }
  }
  system->set_time(time);
}

}  // namespace sim
