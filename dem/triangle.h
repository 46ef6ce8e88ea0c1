// Closest point of a triangle to a point, with the Voronoi region it lies in (face, one of the
// three edges, one of the three vertices). Ericson, Real-Time Collision Detection (2005), 5.1.5:
// the same barycentric region tests, written out for doubles. Public header of the dem module.
#pragma once

#include "dem/vec3.h"

namespace dem {

enum class TriangleRegion : int {
  kFace = 0,
  kEdgeAB,
  kEdgeBC,
  kEdgeCA,
  kVertexA,
  kVertexB,
  kVertexC
};

struct ClosestPoint {
  Vec3 point;  // closest point of the triangle [m]
  TriangleRegion region = TriangleRegion::kFace;
};

inline ClosestPoint ClosestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b,
                                           const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {a, TriangleRegion::kVertexA};
  const Vec3 bp = p - b;
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return {b, TriangleRegion::kVertexB};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return {a + v * ab, TriangleRegion::kEdgeAB};
  }
  const Vec3 cp = p - c;
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return {c, TriangleRegion::kVertexC};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return {a + w * ac, TriangleRegion::kEdgeCA};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b + w * (c - b), TriangleRegion::kEdgeBC};
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return {a + v * ab + w * ac, TriangleRegion::kFace};
}

}  // namespace dem
