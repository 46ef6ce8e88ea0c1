#include "dem/clump.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "dem/system.h"

namespace dem {

// ---------------------------------------------------------------------------------------------
// Templates.

const std::vector<ClumpTemplate>& TetrahedronTemplates() {
  static const std::vector<ClumpTemplate> templates = [] {
    // Regular tetrahedron of side a, centroid at the origin: circumradius R = a sqrt(6) / 4,
    // inradius R / 3. A sphere of radius r tangent to the three faces of a corner has its centre
    // on the centroid-vertex axis, 3 r from the vertex (the faces meet the axis at asin(1/3)).
    const double a = 0.01;
    const double big_r = a * std::sqrt(6.0) / 4.0;
    const Vec3 corner[4] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
    auto add_corners = [&](ClumpTemplate* t, double diameter) {
      const double r = 0.5 * diameter;
      for (const Vec3& c : corner) {
        t->centers.push_back(((big_r - 3.0 * r) / std::sqrt(3.0)) * c);
        t->radii.push_back(r);
      }
    };
    ClumpTemplate t1{"tetra1", {Vec3{}}, {0.002}};
    ClumpTemplate t4{"tetra4", {}, {}};
    add_corners(&t4, 3.5e-3);
    ClumpTemplate t8 = t4;
    t8.name = "tetra8";
    add_corners(&t8, 1.75e-3);
    ClumpTemplate t12 = t8;
    t12.name = "tetra12";
    add_corners(&t12, 0.875e-3);
    return std::vector<ClumpTemplate>{t1, t4, t8, t12};
  }();
  return templates;
}

const ClumpTemplate* FindBuiltinTemplate(const std::string& name) {
  for (const ClumpTemplate& t : TetrahedronTemplates())
    if (t.name == name) return &t;
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// Mass properties.

MassProperties ClumpMassProperties(const ClumpTemplate& t, double density, int cells) {
  const std::string what = "ClumpMassProperties: template '" + t.name + "': ";
  if (t.centers.empty() || t.centers.size() != t.radii.size())
    throw std::invalid_argument(what + "needs as many centres as radii, at least one");
  if (!(density > 0) || !std::isfinite(density))
    throw std::invalid_argument(what + "density must be a finite number > 0");
  if (cells < 4) throw std::invalid_argument(what + "cells must be >= 4");
  // Coordinates relative to the mean centre, so the sums see numbers of the clump's own size.
  Vec3 ref;
  for (const Vec3& c : t.centers) ref += c;
  ref *= 1.0 / static_cast<double>(t.centers.size());
  const size_t s = t.radii.size();
  std::vector<Vec3> c(s);
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (size_t k = 0; k < s; ++k) {
    const double r = t.radii[k];
    if (!(r > 0) || !std::isfinite(r) || !IsFinite(t.centers[k]))
      throw std::invalid_argument(what + "sphere " + std::to_string(k) +
                                  ": expected a finite centre and a radius > 0");
    c[k] = t.centers[k] - ref;
    lo = {std::min(lo.x, c[k].x - r), std::min(lo.y, c[k].y - r), 0};
    hi = {std::max(hi.x, c[k].x + r), std::max(hi.y, c[k].y + r), 0};
  }
  const double h = std::max(hi.x - lo.x, hi.y - lo.y) / cells;
  const int nx = static_cast<int>(std::ceil((hi.x - lo.x) / h));
  const int ny = static_cast<int>(std::ceil((hi.y - lo.y) / h));
  const double area = h * h;
  // Unit-density integrals of 1, x, y, z, x^2, y^2, z^2, xy, xz, yz.
  double v = 0, sx = 0, sy = 0, sz = 0, sxx = 0, syy = 0, szz = 0, sxy = 0, sxz = 0, syz = 0;
  std::vector<std::pair<double, double>> chords;
  for (int j = 0; j < ny; ++j) {
    const double y = lo.y + (j + 0.5) * h;
    for (int i = 0; i < nx; ++i) {
      const double x = lo.x + (i + 0.5) * h;
      chords.clear();
      for (size_t k = 0; k < s; ++k) {
        const double d2 = (x - c[k].x) * (x - c[k].x) + (y - c[k].y) * (y - c[k].y);
        const double r2 = t.radii[k] * t.radii[k];
        if (d2 >= r2) continue;
        const double half = std::sqrt(r2 - d2);
        chords.emplace_back(c[k].z - half, c[k].z + half);
      }
      if (chords.empty()) continue;
      // The union of the chords: sorted by start, merged; z integrals in closed form.
      std::sort(chords.begin(), chords.end());
      double len = 0, z1 = 0, z2 = 0;
      double a = chords[0].first, b = chords[0].second;
      auto close = [&] {
        len += b - a;
        z1 += 0.5 * (b * b - a * a);
        z2 += (b * b * b - a * a * a) / 3.0;
      };
      for (size_t e = 1; e < chords.size(); ++e) {
        if (chords[e].first > b) {
          close();
          a = chords[e].first;
          b = chords[e].second;
        } else {
          b = std::max(b, chords[e].second);
        }
      }
      close();
      v += area * len;
      sx += area * x * len;
      sy += area * y * len;
      sz += area * z1;
      sxx += area * (x * x + h * h / 12.0) * len;
      syy += area * (y * y + h * h / 12.0) * len;
      szz += area * z2;
      sxy += area * x * y * len;
      sxz += area * x * z1;
      syz += area * y * z1;
    }
  }
  MassProperties mp;
  mp.volume = v;
  mp.mass = density * v;
  const Vec3 com{sx / v, sy / v, sz / v};
  mp.center_of_mass = ref + com;
  // Second moments about the CoM (parallel axis), then I = integral (|r|^2 delta - r r^T) dm.
  const double cxx = sxx - v * com.x * com.x, cyy = syy - v * com.y * com.y,
               czz = szz - v * com.z * com.z;
  const double cxy = sxy - v * com.x * com.y, cxz = sxz - v * com.x * com.z,
               cyz = syz - v * com.y * com.z;
  auto& in = mp.inertia;
  in[0][0] = density * (cyy + czz);
  in[1][1] = density * (cxx + czz);
  in[2][2] = density * (cxx + cyy);
  in[0][1] = in[1][0] = -density * cxy;
  in[0][2] = in[2][0] = -density * cxz;
  in[1][2] = in[2][1] = -density * cyz;
  return mp;
}

namespace {

// Unit quaternion of a proper rotation matrix (Shepperd's method: the largest of the four
// candidates for the divisor, so no digits are lost).
Quat QuatFromMatrix(const double m[3][3]) {
  const double tr = m[0][0] + m[1][1] + m[2][2];
  Quat q;
  if (tr >= m[0][0] && tr >= m[1][1] && tr >= m[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + tr);
    q = {0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s};
  } else if (m[0][0] >= m[1][1] && m[0][0] >= m[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]);
    q = {(m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s};
  } else if (m[1][1] >= m[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]);
    q = {(m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s};
  } else {
    const double s = 2.0 * std::sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]);
    q = {(m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s};
  }
  if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
  return Normalized(q);
}

}  // namespace

PrincipalAxes ComputePrincipalAxes(const std::array<std::array<double, 3>, 3>& tensor) {
  double a[3][3], vec[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a[i][j] = 0.5 * (tensor[i][j] + tensor[j][i]);
  // Cyclic Jacobi: rotate away the largest off-diagonal entries until they vanish to rounding.
  for (int sweep = 0; sweep < 50; ++sweep) {
    const double off = std::abs(a[0][1]) + std::abs(a[0][2]) + std::abs(a[1][2]);
    const double diag = std::abs(a[0][0]) + std::abs(a[1][1]) + std::abs(a[2][2]);
    if (off <= 1e-15 * diag || off == 0.0) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0.0) continue;
        const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double cs = 1.0 / std::sqrt(t * t + 1), sn = t * cs;
        for (int k = 0; k < 3; ++k) {  // A <- A J (columns p, q)
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = cs * akp - sn * akq;
          a[k][q] = sn * akp + cs * akq;
        }
        for (int k = 0; k < 3; ++k) {  // A <- J^T A (rows p, q)
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = cs * apk - sn * aqk;
          a[q][k] = sn * apk + cs * aqk;
        }
        for (int k = 0; k < 3; ++k) {  // V <- V J
          const double vkp = vec[k][p], vkq = vec[k][q];
          vec[k][p] = cs * vkp - sn * vkq;
          vec[k][q] = sn * vkp + cs * vkq;
        }
      }
  }
  // Ascending moments; the axes as columns, right handed.
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int l, int r) { return a[l][l] < a[r][r]; });
  double m[3][3];
  for (int col = 0; col < 3; ++col)
    for (int row = 0; row < 3; ++row) m[row][col] = vec[row][order[col]];
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  if (det < 0)
    for (int row = 0; row < 3; ++row) m[row][2] = -m[row][2];
  PrincipalAxes out;
  out.moments = {a[order[0]][order[0]], a[order[1]][order[1]], a[order[2]][order[2]]};
  out.rotation = QuatFromMatrix(m);
  return out;
}

ClumpShape MakeClumpShape(const ClumpTemplate& t) {
  const MassProperties mp = ClumpMassProperties(t, 1.0);
  const PrincipalAxes axes = ComputePrincipalAxes(mp.inertia);
  ClumpShape s;
  s.source = t;
  s.volume = mp.volume;
  s.center_of_mass = mp.center_of_mass;
  s.moments_per_density = axes.moments;
  s.principal = axes.rotation;
  s.radii = t.radii;
  // A spherical top: three moments equal within the accuracy of the grid integration above
  // (kClumpMassCells; its column sums treat z apart from x and y, so the exactly isotropic
  // regular tetrahedra of equal spheres come out anisotropic by 8e-6 (tetra4) to 1.8e-5
  // (tetra8)). It gets the mean moment on every axis, as its symmetry says, and the exact free
  // rotation of ClumpSet::BeginStep.
  const Vec3& m = axes.moments;
  const double spread = std::max({m.x, m.y, m.z}) - std::min({m.x, m.y, m.z});
  s.spherical_top = spread <= kSphericalTopSpread * std::max({m.x, m.y, m.z});
  if (s.spherical_top) {
    const double mean = (m.x + m.y + m.z) / 3;
    s.moments_per_density = {mean, mean, mean};
  }
  s.min_radius = 1e300;
  for (size_t k = 0; k < t.radii.size(); ++k) {
    s.offsets.push_back(RotateInverse(s.principal, t.centers[k] - s.center_of_mass));
    s.bounding_radius = std::max(s.bounding_radius, Norm(s.offsets.back()) + t.radii[k]);
    s.min_radius = std::min(s.min_radius, t.radii[k]);
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// State.

Vec3 Clumps::AngularVelocity(size_t c) const {
  const Vec3& li = l[c];
  const Vec3& in = inertia[c];
  return Rotate(q[c], Vec3{li.x / in.x, li.y / in.y, li.z / in.z});
}

Vec3 Clumps::MemberPosition(size_t c, const ClumpShape& s, size_t k) const {
  return x[c] + Rotate(q[c], s.offsets[k]);
}

int ClumpSet::AddShape(const ClumpTemplate& t) {
  for (size_t k = 0; k < shapes_.size(); ++k) {
    const ClumpTemplate& o = shapes_[k].source;
    bool same = o.name == t.name && o.radii == t.radii && o.centers.size() == t.centers.size();
    for (size_t i = 0; same && i < t.centers.size(); ++i)
      same = o.centers[i].x == t.centers[i].x && o.centers[i].y == t.centers[i].y &&
             o.centers[i].z == t.centers[i].z;
    if (same) return static_cast<int>(k);
  }
  shapes_.push_back(MakeClumpShape(t));
  return static_cast<int>(shapes_.size()) - 1;
}

int64_t ClumpSet::Add(int shape, int material, double density, const Vec3& com, const Quat& q,
                      const Vec3& v, const Vec3& w, const Vec3& gravity,
                      const std::vector<int64_t>& members, Particles& p) {
  const ClumpShape& s = shapes_[shape];
  Clumps& c = state_;
  const size_t k = c.size();
  const double mass = density * s.volume;
  const Vec3 inertia = density * s.moments_per_density;
  const Vec3 w_body = RotateInverse(q, w);
  c.shape.push_back(shape);
  c.material.push_back(material);
  c.mass.push_back(mass);
  c.inertia.push_back(inertia);
  c.x.push_back(com);
  c.v.push_back(v);
  c.q.push_back(q);
  c.l.push_back({inertia.x * w_body.x, inertia.y * w_body.y, inertia.z * w_body.z});
  c.f.push_back(mass * gravity);  // before the first step: gravity alone, as for a sphere
  c.t.push_back(Vec3{});
  c.asleep.push_back(0);
  if (c.first.empty()) c.first.push_back(0);
  c.member.insert(c.member.end(), members.begin(), members.end());
  c.first.push_back(static_cast<int32_t>(c.member.size()));
  for (int64_t id : members) {
    if (id >= static_cast<int64_t>(clump_of_id_.size())) clump_of_id_.resize(id + 1, -1);
    clump_of_id_[id] = static_cast<int32_t>(k);
  }
  // The spheres were appended last: their storage indices are the last S.
  const double inv_i_min = 1.0 / std::min({inertia.x, inertia.y, inertia.z});
  const size_t base = p.size() - members.size();
  for (size_t e = 0; e < members.size(); ++e) {
    const size_t i = base + e;
    index_.push_back(static_cast<int32_t>(i));
    p.mass[i] = mass;
    p.inv_mass[i] = 1.0 / mass;
    p.inv_inertia[i] = inv_i_min;
    p.f[i] = Vec3{};
    p.t[i] = Vec3{};
  }
  Place(k, p, true);
  return static_cast<int64_t>(k);
}

void ClumpSet::Place(size_t c, Particles& p, bool positions) const {
  const Clumps& s = state_;
  const ClumpShape& shape = shapes_[s.shape[c]];
  const Vec3 w = s.AngularVelocity(c);
  for (int32_t e = s.first[c]; e < s.first[c + 1]; ++e) {
    const int32_t i = index_[e];
    if (positions) p.x[i] = s.MemberPosition(c, shape, e - s.first[c]);
    p.v[i] = s.v[c] + Cross(w, p.x[i] - s.x[c]);
    p.w[i] = w;
  }
}

std::vector<int64_t> ClumpSet::RemoveClumpsOf(const std::vector<int64_t>& ids) {
  std::vector<int64_t> out = ids;
  if (empty()) return out;
  Clumps& s = state_;
  std::vector<uint8_t> gone(s.size(), 0);
  for (int64_t id : ids) {
    const int32_t c = ClumpOf(id);
    if (c >= 0) gone[c] = 1;
  }
  // Compact every per-clump array in place; members and their indices follow.
  size_t kept = 0;
  std::vector<int64_t> member;
  std::vector<int32_t> first{0}, index;
  for (size_t c = 0; c < s.size(); ++c) {
    if (gone[c]) {
      for (int32_t e = s.first[c]; e < s.first[c + 1]; ++e) {
        out.push_back(s.member[e]);
        clump_of_id_[s.member[e]] = -1;
      }
      continue;
    }
    s.shape[kept] = s.shape[c];
    s.material[kept] = s.material[c];
    s.mass[kept] = s.mass[c];
    s.inertia[kept] = s.inertia[c];
    s.x[kept] = s.x[c];
    s.v[kept] = s.v[c];
    s.q[kept] = s.q[c];
    s.l[kept] = s.l[c];
    s.f[kept] = s.f[c];
    s.t[kept] = s.t[c];
    s.asleep[kept] = s.asleep[c];
    for (int32_t e = s.first[c]; e < s.first[c + 1]; ++e) {
      member.push_back(s.member[e]);
      index.push_back(index_[e]);
      clump_of_id_[s.member[e]] = static_cast<int32_t>(kept);
    }
    first.push_back(static_cast<int32_t>(member.size()));
    ++kept;
  }
  for (auto* a : {&s.shape, &s.material}) a->resize(kept);
  s.mass.resize(kept);
  for (auto* a : {&s.inertia, &s.x, &s.v, &s.l, &s.f, &s.t}) a->resize(kept);
  s.q.resize(kept);
  s.asleep.resize(kept);
  s.member.swap(member);
  s.first.swap(first);
  index_.swap(index);
  return out;
}

const int32_t* ClumpSet::Reindex(const Particles& p, int64_t next_id) {
  if (empty()) return nullptr;
  std::vector<int32_t> index_of_id(static_cast<size_t>(next_id), -1);
  for (size_t i = 0; i < p.size(); ++i) index_of_id[p.id[i]] = static_cast<int32_t>(i);
  for (size_t e = 0; e < state_.member.size(); ++e) index_[e] = index_of_id[state_.member[e]];
  clump_of_index_.resize(p.size());
  for (size_t i = 0; i < p.size(); ++i) clump_of_index_[i] = ClumpOf(p.id[i]);
  return clump_of_index_.data();
}

// ---------------------------------------------------------------------------------------------
// Integration.

namespace {

// The exact flow of the free-rotor term L_k^2 / (2 I_k) for a time tau: the body turns by
// theta = tau L_k / I_k about its principal axis k (q <- q (cos theta/2, sin theta/2 e_k)), and
// its angular momentum in the body frame turns by -theta about the same axis (Euler's equations,
// dL/dt = L x w, with w = (L_k / I_k) e_k). World L = R L is unchanged by construction.
void FreeRotation(int k, double tau, const Vec3& inertia, Quat* q, Vec3* l) {
  double lb[3] = {l->x, l->y, l->z};
  const double in[3] = {inertia.x, inertia.y, inertia.z};
  const double theta = tau * lb[k] / in[k];
  const double c = std::cos(theta), s = std::sin(theta);
  const int a = (k + 1) % 3, b = (k + 2) % 3;
  const double la = c * lb[a] + s * lb[b];
  const double lbb = -s * lb[a] + c * lb[b];
  lb[a] = la;
  lb[b] = lbb;
  *l = {lb[0], lb[1], lb[2]};
  const double ch = std::cos(0.5 * theta), sh = std::sin(0.5 * theta);
  const Quat turn{ch, k == 0 ? sh : 0.0, k == 1 ? sh : 0.0, k == 2 ? sh : 0.0};
  *q = *q * turn;
}

}  // namespace

ClumpSet::BeginReport ClumpSet::BeginStep(Particles& p, double dt, int threads, uint8_t* moved,
                                          double* inv_spin, const std::vector<int32_t>* awake) {
  BeginReport report;
  Clumps& s = state_;
  const int64_t n = static_cast<int64_t>(s.size());
  // A sleeping clump with an awake sphere (touched, in a mesh zone, or sleeping switched off)
  // wakes whole, at rest in equilibrium like a waking sphere. Where the clump of each storage
  // index is known, the clumps to wake are found from the awake spheres (the list given, else
  // one sequential pass over storage), else from each sleeping clump's spheres (which lie
  // anywhere in storage).
  const int32_t* clump_of = clump_of_index(p.size());
  const bool indexed = clump_of != nullptr;
  if (indexed) {
    waking_.assign(static_cast<size_t>(n), 0);
    const auto mark = [&](size_t i) {
      if (p.awake[i] != 0 && clump_of[i] >= 0 && s.asleep[clump_of[i]]) waking_[clump_of[i]] = 1;
    };
    if (awake != nullptr) {
      for (const int32_t i : *awake) mark(static_cast<size_t>(i));
    } else {
      for (size_t i = 0; i < p.size(); ++i) mark(i);
    }
  }
  for (int64_t c = 0; c < n; ++c) {
    if (!s.asleep[c]) continue;
    if (indexed) {
      if (!waking_[c]) continue;
    } else {
      bool any = false;
      for (int32_t e = s.first[c]; e < s.first[c + 1]; ++e) any = any || p.awake[index_[e]] != 0;
      if (!any) continue;
    }
    s.asleep[c] = 0;
    s.v[c] = s.l[c] = s.f[c] = s.t[c] = Vec3{};
    for (int32_t e = s.first[c]; e < s.first[c + 1]; ++e) {
      const int32_t i = index_[e];
      if (p.awake[i] == 0) report.woke = true;
      p.awake[i] = 1;
      if (moved != nullptr) moved[i] = 1;
    }
  }
  // Half kick, drift, placement (velocity Verlet; DLM splitting for the rotation).
  const double h = 0.5 * dt;
  double max2 = 0;
#pragma omp parallel for schedule(static) num_threads(threads) reduction(max : max2)
  for (int64_t c = 0; c < n; ++c) {
    if (s.asleep[c]) continue;
    const ClumpShape& shape = shapes_[s.shape[c]];
    const Vec3 x0 = s.x[c];
    const Quat q0 = s.q[c];
    s.v[c] += (h / s.mass[c]) * s.f[c];
    s.l[c] += h * RotateInverse(s.q[c], s.t[c]);
    s.x[c] += dt * s.v[c];
    Quat q = s.q[c];
    Vec3 l = s.l[c];
    if (shape.spherical_top) {
      // A spherical top (I1 = I2 = I3): w = L / I is parallel to L, so Euler's equations give
      // dL/dt = L x w = 0 in the body frame, and the free flow over dt is exact as one turn by
      // |w| dt about w (Goldstein, Classical Mechanics, sec. 5.5). The splitting below is a
      // second-order approximation of the same flow at ten times the sines and cosines.
      const Vec3& in = s.inertia[c];
      const Vec3 wb{l.x / in.x, l.y / in.y, l.z / in.z};
      const double rate = Norm(wb);
      if (rate > 0) {
        const double half = 0.5 * dt * rate;
        const double k = std::sin(half) / rate;
        q = q * Quat{std::cos(half), k * wb.x, k * wb.y, k * wb.z};
      }
    } else {
      // DLM splitting (Dullweber, Leimkuhler, McLachlan, J. Chem. Phys. 107, 5840 (1997)).
      FreeRotation(0, h, s.inertia[c], &q, &l);
      FreeRotation(1, h, s.inertia[c], &q, &l);
      FreeRotation(2, dt, s.inertia[c], &q, &l);
      FreeRotation(1, h, s.inertia[c], &q, &l);
      FreeRotation(0, h, s.inertia[c], &q, &l);
    }
    s.q[c] = Normalized(q);
    s.l[c] = l;
    const Vec3 w = s.AngularVelocity(c);
    const double inv_w = inv_spin != nullptr ? InvNorm(w) : 0.0;
    for (int32_t e = s.first[c]; e < s.first[c + 1]; ++e) {
      const int32_t i = index_[e];
      const Vec3 r = Rotate(s.q[c], shape.offsets[e - s.first[c]]);
      // Where the sphere was: with the index, KickDrift left it where the last placement (this
      // loop, Place) put it, x0 + Rotate(q0, offset), bit for bit; without, it drifted as a free
      // sphere, and the placement is made again.
      const Vec3 before = indexed ? p.x[i] : x0 + Rotate(q0, shape.offsets[e - s.first[c]]);
      p.x[i] = s.x[c] + r;
      p.v[i] = s.v[c] + Cross(w, r);
      p.w[i] = w;
      p.f[i] = Vec3{};
      p.t[i] = Vec3{};
      if (inv_spin != nullptr) inv_spin[i] = inv_w;
      max2 = std::max(max2, Norm2(p.x[i] - before));
    }
  }
  // (max over a / c = (max over a) / c for c > 0: rounding keeps the order)
  report.max_member_speed2 = max2 / (dt * dt);
  return report;
}

bool ClumpSet::EndStep(Particles& p, const Vec3& gravity, double dt, int threads) {
  Clumps& s = state_;
  const int64_t n = static_cast<int64_t>(s.size());
  const double h = 0.5 * dt;
  int bad = 0;
#pragma omp parallel for schedule(static) num_threads(threads) reduction(| : bad)
  for (int64_t c = 0; c < n; ++c) {
    if (s.asleep[c]) continue;
    // Force and torque about the CoM, summed in template order (fixed: deterministic).
    Vec3 f = s.mass[c] * gravity, t;
    for (int32_t e = s.first[c]; e < s.first[c + 1]; ++e) {
      const int32_t i = index_[e];
      f += p.f[i];
      t += Cross(p.x[i] - s.x[c], p.f[i]) + p.t[i];
    }
    s.f[c] = f;
    s.t[c] = t;
    s.v[c] += (h / s.mass[c]) * f;
    s.l[c] += h * RotateInverse(s.q[c], t);
    if (!(IsFinite(s.v[c]) && IsFinite(s.l[c]) && IsFinite(s.x[c]))) bad = 1;
    Place(c, p, false);
  }
  return bad == 0;
}

bool ClumpSet::SyncSleep(Particles& p, int quiet_checks) {
  Clumps& s = state_;
  const int asleep_key = quiet_checks + 2;
  bool changed = false;
  for (size_t c = 0; c < s.size(); ++c) {
    if (s.asleep[c]) continue;
    int lowest = asleep_key;
    for (int32_t e = s.first[c]; e < s.first[c + 1]; ++e) {
      const uint8_t a = p.awake[index_[e]];
      lowest = std::min(lowest, a == 0 ? asleep_key : static_cast<int>(a));
    }
    if (lowest == asleep_key) {  // every sphere fell asleep at this check: the clump sleeps
      s.asleep[c] = 1;
      s.v[c] = s.l[c] = Vec3{};
      changed = true;
      continue;
    }
    bool restored = false;
    for (int32_t e = s.first[c]; e < s.first[c + 1]; ++e) {
      uint8_t& a = p.awake[index_[e]];
      restored = restored || a == 0;
      a = static_cast<uint8_t>(lowest);
    }
    if (restored) Place(c, p, false);  // spheres put to sleep lost their velocities
    changed = changed || restored;
  }
  return changed;
}

double ClumpSet::KineticEnergy() const {
  const Clumps& s = state_;
  double e = 0;
  for (size_t c = 0; c < s.size(); ++c) {
    const Vec3& l = s.l[c];
    const Vec3& in = s.inertia[c];
    e += 0.5 * s.mass[c] * Norm2(s.v[c]) +
         0.5 * (l.x * l.x / in.x + l.y * l.y / in.y + l.z * l.z / in.z);
  }
  return e;
}

double ClumpSet::PotentialEnergy(const Vec3& gravity) const {
  double e = 0;
  for (size_t c = 0; c < state_.size(); ++c) e -= state_.mass[c] * Dot(gravity, state_.x[c]);
  return e;
}

Vec3 ClumpSet::Momentum() const {
  Vec3 m;
  for (size_t c = 0; c < state_.size(); ++c) m += state_.mass[c] * state_.v[c];
  return m;
}

// ---------------------------------------------------------------------------------------------
// System::AddClump stays here, the one method of dem::System (dem/system.h) outside system.cpp:
// it places a clump's spheres by quaternion products (pose x principal axes, Rotate), the sums of
// products that GCC's SLP vectorizer fuses into vfmaddsub despite -ffp-contract=off, so it keeps
// this file's -mno-fma -mno-avx512f (dem/CMakeLists.txt, top-level CMakeLists.txt) with
// ComputePrincipalAxes, while system.cpp is built for the machine's full vector units. The rest
// of the System's clump API (accessors, no arithmetic) is in system.cpp.

int64_t System::AddClump(int shape, const Pose& pose, const Vec3& v, const Vec3& w, int material) {
  const ClumpShape& s = clumps_.shapes()[shape];
  const Vec3 com = Apply(pose, s.center_of_mass);
  const Quat q = Normalized(pose.orientation * s.principal);
  std::vector<int64_t> members;
  for (size_t k = 0; k < s.size(); ++k)
    members.push_back(AddParticle(com + Rotate(q, s.offsets[k]), v, w, s.radii[k], material));
  return clumps_.Add(shape, material, materials_[material].density, com, q, v, w, config_.gravity,
                     members, p_);
}

}  // namespace dem
