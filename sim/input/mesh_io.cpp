#include "sim/input/mesh_io.h"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <utility>

#include "sim/input/input_error.h"

namespace sim {

namespace {

constexpr const char* kExpected =
    "a triangle mesh file that assimp reads (STL, OBJ, PLY, glTF, ...)";

// The file as a whole is wrong: no key (the caller reports it under its own key for the file).
[[noreturn]] void Fail(const std::string& path, const std::string& expected,
                       const std::string& got) {
  throw InputError(path, 0, "", expected, got);
}

// An affine transform in double precision: x' = r x + t (rows of r).
struct Affine {
  std::array<std::array<double, 3>, 3> r{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  dem::Vec3 t;

  dem::Vec3 Apply(const dem::Vec3& x) const {
    return {r[0][0] * x.x + r[0][1] * x.y + r[0][2] * x.z + t.x,
            r[1][0] * x.x + r[1][1] * x.y + r[1][2] * x.z + t.y,
            r[2][0] * x.x + r[2][1] * x.y + r[2][2] * x.z + t.z};
  }
  double Determinant() const {
    return r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) -
           r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0]) +
           r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
  }
};

// assimp's node matrix (row-major, acting on column vectors; the last row is 0 0 0 1).
Affine FromAssimp(const aiMatrix4x4& m) {
  Affine a;
  a.r = {{{m.a1, m.a2, m.a3}, {m.b1, m.b2, m.b3}, {m.c1, m.c2, m.c3}}};
  a.t = {m.a4, m.b4, m.c4};
  return a;
}

// parent o child: x -> parent(child(x)).
Affine Compose(const Affine& parent, const Affine& child) {
  Affine out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      out.r[i][j] = parent.r[i][0] * child.r[0][j] + parent.r[i][1] * child.r[1][j] +
                    parent.r[i][2] * child.r[2][j];
    }
  }
  out.t = parent.Apply(child.t);
  return out;
}

// Appends the triangles of every mesh under `node`, placed by the accumulated node transforms.
void AppendNode(const aiScene& scene, const aiNode& node, const Affine& parent,
                dem::TriangleMesh* out) {
  const Affine global = Compose(parent, FromAssimp(node.mTransformation));
  const bool mirrored = global.Determinant() < 0;
  for (unsigned k = 0; k < node.mNumMeshes; ++k) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[k]];
    const int32_t base = static_cast<int32_t>(out->vertices.size());
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      out->vertices.push_back(global.Apply({p.x, p.y, p.z}));
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines
      std::array<int32_t, 3> tri{base + static_cast<int32_t>(face.mIndices[0]),
                                 base + static_cast<int32_t>(face.mIndices[1]),
                                 base + static_cast<int32_t>(face.mIndices[2])};
      if (mirrored) std::swap(tri[1], tri[2]);
      out->triangles.push_back(tri);
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    AppendNode(scene, *node.mChildren[c], global, out);
  }
}

}  // namespace

dem::TriangleMesh LoadMesh(const std::string& path, double scale) {
  if (!(scale > 0) || !std::isfinite(scale)) {
    std::ostringstream got;
    got << scale;
    throw InputError(path, 0, "scale", "a finite number > 0 (mesh units to m)", got.str());
  }
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) Fail(path, kExpected, "a folder");
  if (!std::filesystem::is_regular_file(path, ec)) Fail(path, kExpected, "no such file");

  // Positions only: with normals (flat-shaded STL) or texture coordinates still attached, the
  // corners that faces share would not be joined.
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                  aiComponent_COLORS | aiComponent_TEXCOORDS |
                                  aiComponent_BONEWEIGHTS);
  // Coordinates as written: no Collada up-axis turn (its unit is still applied).
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_RemoveComponent | aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    std::string why = importer.GetErrorString();
    std::replace(why.begin(), why.end(), '\n', ' ');  // one line
    Fail(path, kExpected, "a file assimp cannot read (assimp: " + why + ")");
  }

  dem::TriangleMesh mesh;
  mesh.name = path;
  AppendNode(*scene, *scene->mRootNode, Affine{}, &mesh);
  if (mesh.triangles.empty()) {
    Fail(path, kExpected, "a file that holds no triangle");
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    dem::Vec3& v = mesh.vertices[i];
    v *= scale;
    if (!dem::IsFinite(v)) {
      std::ostringstream got;
      got << "vertex " << i << " at (" << v.x << ", " << v.y << ", " << v.z << ")";
      Fail(path, "a mesh whose vertices have finite coordinates", got.str());
    }
  }
  // Zero-area triangles (coincident or collinear corners): a broken export, whose contacts
  // would meet edges where the surface should be. Zero relative to the mesh's own size.
  dem::Vec3 lo = mesh.vertices.front(), hi = lo;
  for (const dem::Vec3& v : mesh.vertices) {
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
  // Edges in units of the box's diagonal (an overflowing size is the scale check's to refuse).
  const double size = std::sqrt(dem::Dot(hi - lo, hi - lo));
  const double inv = std::isfinite(size) && size > 0 ? 1 / size : 0;
  size_t degenerate = size == 0 ? mesh.triangles.size() : 0, first = 0;
  for (size_t t = 0; inv > 0 && t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const dem::Vec3 a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]], c = mesh.vertices[tri[2]];
    const dem::Vec3 n = dem::Cross((b - a) * inv, (c - a) * inv);
    if (!(dem::Dot(n, n) > 1e-24)) {
      if (degenerate++ == 0) first = t;
    }
  }
  if (degenerate > 0) {
    std::ostringstream got;
    got << degenerate << " of " << mesh.triangles.size()
        << " triangles with zero area (the first: triangle " << first << ")";
    Fail(path, "a mesh whose triangles have non-zero area", got.str());
  }
  return mesh;
}

}  // namespace sim
