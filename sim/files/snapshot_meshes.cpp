// The meshes of a snapshot (the scoop, the arm's links, obstacles) in the HDF5 file and the XDMF
// sidecar (sim/files/internal_h5.h: WriteSnapshotMeshes, MeshGridsXdmf), apart from the particles' own
// writer so that each stays short.
#include <hdf5.h>

#include <sstream>
#include <string>
#include <vector>

#include "sim/files/internal_h5.h"

namespace sim::h5 {

std::vector<MeshEntry> WriteSnapshotMeshes(hid_t group, const std::vector<MeshView>& meshes) {
  // The roles in order of first appearance.
  std::vector<MeshRole> roles;
  for (const MeshView& m : meshes) {
    bool seen = false;
    for (MeshRole r : roles) seen |= r == m.role;
    if (m.mesh != nullptr && !seen) roles.push_back(m.role);
  }
  std::vector<MeshEntry> entries;
  for (MeshRole role : roles) {
    std::vector<double> points, pose;
    std::vector<int64_t> triangles;
    std::vector<int32_t> part;
    int32_t parts = 0;
    for (const MeshView& m : meshes) {
      if (m.mesh == nullptr || m.role != role) continue;
      const int64_t base = static_cast<int64_t>(points.size() / 3);
      for (const dem::Vec3& v : m.mesh->vertices) {
        const dem::Vec3 p = dem::Apply(m.pose, v);
        points.insert(points.end(), {p.x, p.y, p.z});
      }
      for (const auto& t : m.mesh->triangles) {
        triangles.insert(triangles.end(), {base + t[0], base + t[1], base + t[2]});
        part.push_back(parts);
      }
      const dem::Pose& q = m.pose;
      pose.insert(pose.end(), {q.position.x, q.position.y, q.position.z, q.orientation.w,
                               q.orientation.x, q.orientation.y, q.orientation.z});
      ++parts;
    }
    MeshEntry entry{MeshRoleName(role), static_cast<int64_t>(points.size() / 3),
                    static_cast<int64_t>(part.size())};
    // Relative to the snapshot's group, which is not in the tree yet (LinkWhenWritten).
    const std::string name = "meshes/" + entry.name;
    Handle lcpl(CheckId(H5Pcreate(H5P_LINK_CREATE), "H5Pcreate"), H5Pclose);
    CheckOk(H5Pset_create_intermediate_group(lcpl.get(), 1), "H5Pset_create_intermediate_group");
    Handle g(CheckId(H5Gcreate2(group, name.c_str(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT),
                     "H5Gcreate2 " + name),
             H5Gclose);
    const hsize_t v = static_cast<hsize_t>(entry.points), t = static_cast<hsize_t>(entry.triangles);
    WriteArray(g.get(), "points", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, points.data(), v, 3);
    WriteArray(g.get(), "triangles", H5T_STD_I64LE, H5T_NATIVE_INT64, triangles.data(), t, 3);
    WriteArray(g.get(), "part", H5T_STD_I32LE, H5T_NATIVE_INT32, part.data(), t, 1);
    WriteArray(g.get(), "pose", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, pose.data(),
               static_cast<hsize_t>(parts), 7);
    MarkQuaternions(g.get(), "pose", true);
    entries.push_back(std::move(entry));
  }
  return entries;
}

std::string MeshGridsXdmf(const std::string& h5_file_name,
                          const std::vector<SnapshotEntry>& snapshots) {
  // The names in order of first appearance; a temporal collection each, with a grid at every
  // snapshot that holds that name.
  std::vector<std::string> names;
  for (const SnapshotEntry& s : snapshots)
    for (const MeshEntry& m : s.meshes) {
      bool seen = false;
      for (const std::string& n : names) seen |= n == m.name;
      if (!seen) names.push_back(m.name);
    }
  std::ostringstream x;
  for (const std::string& name : names) {
    x << "    <Grid Name=\"" << name << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (const SnapshotEntry& s : snapshots) {
      for (const MeshEntry& m : s.meshes) {
        if (m.name != name) continue;
        const std::string path = h5_file_name + ":" + s.group + "/meshes/" + name + "/";
        const std::string t = std::to_string(m.triangles), v = std::to_string(m.points);
        x << "      <Grid Name=\"" << s.group.substr(s.group.rfind('/') + 1)
          << "\" GridType=\"Uniform\">\n"
          << "        <Time Value=\"" << FormatDouble(s.time) << "\"/>\n"
          << "        <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << t << "\">\n"
          << "          <DataItem Dimensions=\"" << t << " 3\" NumberType=\"Int\" Precision=\"8\" "
          << "Format=\"HDF\">" << path << "triangles</DataItem>\n"
          << "        </Topology>\n"
          << "        <Geometry GeometryType=\"XYZ\">\n"
          << "          <DataItem Dimensions=\"" << v
          << " 3\" NumberType=\"Float\" Precision=\"8\" "
          << "Format=\"HDF\">" << path << "points</DataItem>\n"
          << "        </Geometry>\n"
          << "        <Attribute Name=\"part\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
          << "          <DataItem Dimensions=\"" << t << "\" NumberType=\"Int\" Precision=\"4\" "
          << "Format=\"HDF\">" << path << "part</DataItem>\n"
          << "        </Attribute>\n"
          << "      </Grid>\n";
      }
    }
    x << "    </Grid>\n";
  }
  return x.str();
}

}  // namespace sim::h5
