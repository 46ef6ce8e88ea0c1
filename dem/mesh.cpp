#include "dem/mesh.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace dem {

namespace {

// Eberly's subexpressions for one coordinate w of a triangle's three vertices: f1, f2, f3 are the
// sums that integrate w, w^2 and w^3 over the triangle; g0, g1, g2 serve the mixed products.
struct Subexpressions {
  double f1, f2, f3, g0, g1, g2;
};

Subexpressions Subexpr(double w0, double w1, double w2) {
  const double temp0 = w0 + w1;
  const double f1 = temp0 + w2;
  const double temp1 = w0 * w0;
  const double temp2 = temp1 + w1 * temp0;
  const double f2 = temp2 + w2 * f1;
  const double f3 = w0 * temp1 + w1 * temp2 + w2 * f2;
  return {f1, f2, f3, f2 + w0 * (f1 + w0), f2 + w1 * (f1 + w1), f2 + w2 * (f1 + w2)};
}

std::string Str(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

MeshError::MeshError(const std::string& mesh, std::string field, std::string expected,
                     std::string got)
    : std::invalid_argument("mesh '" + mesh + "': " + field + ": expected " + expected + ", got " +
                            got),
      field_(std::move(field)),
      expected_(std::move(expected)),
      got_(std::move(got)) {}

MassProperties ComputeMassProperties(const TriangleMesh& mesh, double density) {
  if (!(density > 0) || !std::isfinite(density)) {
    throw MeshError(mesh.name, "density", "a finite number > 0 [kg/m^3]", Str(density));
  }
  // Reference point: the mean vertex, so the integrals see coordinates of the mesh's own size.
  Vec3 ref;
  for (const Vec3& v : mesh.vertices) ref += v;
  if (!mesh.vertices.empty()) ref *= 1.0 / static_cast<double>(mesh.vertices.size());

  // Volume integrals of 1, x, y, z, x^2, y^2, z^2, xy, yz, zx (unit density), summed over the
  // triangles in storage order (Eberly 2002, algorithm "Compute").
  double intg[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  const int32_t n_vertices = static_cast<int32_t>(mesh.vertices.size());
  for (const auto& tri : mesh.triangles) {
    for (int32_t i : tri) {
      if (i < 0 || i >= n_vertices) {
        throw MeshError(mesh.name, "triangles",
                        "vertex indices in [0, " + std::to_string(n_vertices) + ")",
                        "index " + std::to_string(i));
      }
    }
    const Vec3 p0 = mesh.vertices[tri[0]] - ref;
    const Vec3 p1 = mesh.vertices[tri[1]] - ref;
    const Vec3 p2 = mesh.vertices[tri[2]] - ref;
    const Vec3 d = Cross(p1 - p0, p2 - p0);  // twice the area times the outward normal
    const Subexpressions sx = Subexpr(p0.x, p1.x, p2.x);
    const Subexpressions sy = Subexpr(p0.y, p1.y, p2.y);
    const Subexpressions sz = Subexpr(p0.z, p1.z, p2.z);
    intg[0] += d.x * sx.f1;
    intg[1] += d.x * sx.f2;
    intg[2] += d.y * sy.f2;
    intg[3] += d.z * sz.f2;
    intg[4] += d.x * sx.f3;
    intg[5] += d.y * sy.f3;
    intg[6] += d.z * sz.f3;
    intg[7] += d.x * (p0.y * sx.g0 + p1.y * sx.g1 + p2.y * sx.g2);
    intg[8] += d.y * (p0.z * sy.g0 + p1.z * sy.g1 + p2.z * sy.g2);
    intg[9] += d.z * (p0.x * sz.g0 + p1.x * sz.g1 + p2.x * sz.g2);
  }
  const double scale[10] = {1.0 / 6,  1.0 / 24, 1.0 / 24,  1.0 / 24,  1.0 / 60,
                            1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
  for (int k = 0; k < 10; ++k) intg[k] *= scale[k];

  const double volume = intg[0];
  if (!(volume > 0)) {
    throw MeshError(mesh.name, "volume",
                    "an enclosed volume > 0 (a closed mesh, counter-clockwise seen from outside)",
                    Str(volume) + " m^3");
  }

  // Centre of mass relative to `ref`, then the second moments moved to it (parallel axes).
  const Vec3 c{intg[1] / volume, intg[2] / volume, intg[3] / volume};
  const double xx = intg[4] - volume * c.x * c.x;  // integral of (x - cx)^2 dV
  const double yy = intg[5] - volume * c.y * c.y;
  const double zz = intg[6] - volume * c.z * c.z;
  const double xy = intg[7] - volume * c.x * c.y;
  const double yz = intg[8] - volume * c.y * c.z;
  const double zx = intg[9] - volume * c.z * c.x;

  MassProperties out;
  out.volume = volume;
  out.mass = density * volume;
  out.center_of_mass = ref + c;
  out.inertia = {{{density * (yy + zz), -density * xy, -density * zx},
                  {-density * xy, density * (zz + xx), -density * yz},
                  {-density * zx, -density * yz, density * (xx + yy)}}};
  return out;
}

}  // namespace dem
