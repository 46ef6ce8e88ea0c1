// Triangle meshes from files (the scoop): any format assimp reads (STL, OBJ, PLY, glTF, ...),
// into a dem::TriangleMesh in SI units. Public header of the sim module; assimp stays inside
// mesh_io.cpp.
#pragma once

#include <string>

#include "dem/mesh.h"

namespace sim {

// Reads every mesh of the file at `path` into one dem::TriangleMesh: polygons triangulated,
// identical vertices joined (positions only: normals, colours and texture coordinates are dropped
// first, so the corners of a flat-shaded STL are shared), each mesh placed by its node transforms
// (a mirroring transform flips the triangles back to counter-clockwise seen from outside), then
// every coordinate multiplied by `scale` (say 0.001 for a file in millimetres). Points and lines
// are skipped. Coordinates are taken as written: no up-axis conversion (Collada's Z_UP is
// ignored; its unit is applied). The winding is the file's: a closed mesh should be
// counter-clockwise seen from outside. Debian's assimp holds coordinates in single precision: a
// vertex carries a relative error of about 6e-8 (a few nm on the scoop). name = `path`,
// material = 0 (the caller sets it).
// Throws sim::InputError, one line naming the file and what was expected, when the file is missing
// or unreadable, holds no triangle, a vertex is not finite (key() ""), or scale is not a finite
// number > 0 (key() "scale"). A scene reports it under its own key (sim::LoadScene).
dem::TriangleMesh LoadMesh(const std::string& path, double scale = 1.0);

}  // namespace sim
