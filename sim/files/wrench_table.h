// The wrench lookup table (paper eq. 1, Table 5): f(material, bite depth, pass, rho) -> the six
// components of the wrench of the particles on the scoop, built from a sweep's cases, queried
// with linear interpolation, and exported as the lander simulator's CSV.
//
// Resampling (BuildWrenchTable): for each case (a material and a bite depth) and each of its
// passes, the /scoop/ rows of that pass from its first row with a particle-scoop contact on, with
// rho (the CoM's travel along the trench since first contact) made monotone as its running
// maximum: a row enters only where it raises that maximum (the rows where the scoop stands
// or moves back along the trench, mostly the final rotation, do not: rho does not resolve
// them). The wrench at each node of the common grid rho_k = k * step (0..rho_max) is linear in
// rho between the two rows around it; below the first row it is the first row's; past the
// pass's last row (its rho_end) there is no data and the table holds NaN. A lander sim asks for
// rho beyond a pass's end only when its scoop goes on past where the DEM's did: Query then says
// so (OutOfTableDomain) unless asked to clamp, and the CSV export leaves those rows out, so the
// lander's nearest-key lookup holds the pass's last value there.
//
// TABLE.h5 layout (SI units; M materials, B bite depths, P passes, R rho nodes):
//   /                     attributes kind ("scoopsim wrench table"), version, rho_step, rho_max
//                         [m], units, frames, resample (the rule above), particle_size (one line
//                         per material), material_ids ("snow=1, ice=2")
//   /materials/name       (M) strings, ordered by id; /materials/id int32 (M) (LanderMaterialId);
//   /materials/particle_size (M) strings ("spheres r 8 mm", "clumps tetra4 ...")
//   /bite_depth           (B) [m], ascending
//   /pass                 (P) int32, 1..P
//   /rho                  (R) [m]: rho_k = k * rho_step
//   /scoop/force_body, /scoop/torque_body     (M x B x P x R x 3) [N], [N m] in the study's body
//                         frame; /scoop/force_scoop, /scoop/torque_scoop in the l_scoop frame;
//                         about the scoop's CoM (sim/loop/dig.h); NaN where there is no data
//   /cells/rho_end        (M x B x P) [m] rho of the pass's last row used; NaN: no case or no
//                         contact in that pass
//   /cells/rows           (M x B x P) int32: rows of the pass used (0: none)
//   /cells/case           (M x B) strings: the case each (material, bite depth) came from
//   /cases/name, /cases/file, /cases/scene_yaml   (C) strings: every source case, its file
//                         (relative to the sweep folder: cases/<name>.h5) and its scene text
#pragma once

#include <array>
#include <string>
#include <vector>

#include "sim/input/scene.h"

namespace sim {

class H5Output;  // sim/files/h5_output.h

// The material ids of the lander simulator's CSV (column m): snow 1, ice 2, sand 3 (fixed);
// another material gets 10, 11, ... in the order of its name among the table's other materials
// (the table's /materials/id and the export say which).
int LanderMaterialId(const std::string& name);  // 0 when it has no fixed id

// What rho measures, from the scoop's first contact in the pass: kPath the length of the path
// of the scoop's CoM (/scoop/rho_path; the study's and the lander's table's rho), kAlong the
// CoM's displacement along the trench (/scoop/rho). docs/studies.md "The table's rho" gives the
// evidence for kPath.
enum class RhoDefinition { kPath, kAlong };
const char* RhoDefinitionName(RhoDefinition d);  // "path" or "along"

struct WrenchTableOptions {
  double rho_step_mm = 2;   // grid step [mm] (the lander's table: ~2 mm)
  double rho_max_mm = 450;  // grid end [mm]
  RhoDefinition rho = RhoDefinition::kPath;
};

// The cell of the table a case fills, from its validated scene: bed.material, dig.bite_depth and
// the particles' size ("spheres r 8 mm", "spheres r 4 mm to 8 mm", "clumps tetra4").
struct TableCell {
  std::string material;
  double bite_depth = 0;  // [m]
  std::string particle_size;
};
TableCell TableCellOf(const Scene& scene);
// Writes TableCellOf(scene) as root attributes of a case's output (table_material,
// table_bite_depth [m], table_particle_size), which BuildWrenchTable reads.
void WriteTableCell(const Scene& scene, H5Output* out);

// `scoopsim table build DIR -o TABLE.h5`: the table of every DIR/cases/*.h5 (a run's output with
// a dig; its cell from the attributes WriteTableCell wrote, or, in a case file made before them,
// from its stored scene text: sim::ParseStoredDig). Throws
// InputError for a folder without cases, two cases of one material and bite depth, or a file
// that is not a dig's output. Returns a one-line summary.
std::string BuildWrenchTable(const std::string& dir, const std::string& table_path,
                             const WrenchTableOptions& options = {});

// Arguments outside a table's domain: a material, pass or bite depth it does not hold, rho
// outside its grid or past the end of the data of a pass. An InputError (the CLI exits 2).
class OutOfTableDomain : public InputError {
 public:
  using InputError::InputError;
};

class WrenchTable {
 public:
  enum class Frame { kScoop, kBody };  // l_scoop (the lander's) or the study's body frame

  // Loads TABLE.h5 whole. Throws InputError naming the file and the dataset when it is not one.
  explicit WrenchTable(const std::string& path);

  // [Fx Fy Fz Tx Ty Tz] ([N], [N m]) about the scoop's CoM in `frame`: exact in material and
  // pass, linear in bite depth (between the table's two nearest) and in rho (between grid
  // nodes); a value within 1e-9 mm of a stored bite depth or a grid node is that one, so stored
  // samples come back exactly. Out of the domain: OutOfTableDomain, unless `clamp`, which puts
  // the bite depth and rho into the table's range and holds the value at the last grid node
  // with data past a pass's end (material and pass are never clamped).
  std::array<double, 6> Query(const std::string& material, double bite_depth_mm, int pass,
                              double rho_mm, bool clamp = false, Frame frame = Frame::kScoop) const;

  // The lander simulator's CSV: header m,d,p,rho,Fx,Fy,Fz,Tx,Ty,Tz; m the material id, d the
  // bite depth [m], p the pass, rho [m], the wrench in the l_scoop frame about the CoM [N, N m];
  // one row per grid node with data, by material id, bite depth, pass and rho. Numbers in
  // their shortest form that reads back to the same double; with `digits` (1-17) the wrench
  // with that many significant digits (a smaller file; the keys stay exact).
  void ExportCsv(const std::string& csv_path, int digits = 0) const;

  const std::string& path() const { return path_; }
  const std::vector<std::string>& materials() const { return materials_; }
  const std::vector<int>& material_ids() const { return material_ids_; }
  const std::vector<double>& bite_depths() const { return bite_depths_; }  // [m]
  const std::vector<int>& passes() const { return passes_; }
  const std::vector<double>& rho() const { return rho_; }  // [m]
  RhoDefinition rho_definition() const { return rho_definition_; }
  double rho_step() const { return rho_step_; }  // [m]
  // The stored sample of cell (m, b, p) at grid node r: the six components in `frame`.
  std::array<double, 6> Sample(int m, int b, int p, int r, Frame frame = Frame::kScoop) const;
  double RhoEnd(int m, int b, int p) const;  // [m]; NaN when the cell has no data

 private:
  size_t Cell(int m, int b, int p) const;
  // The value of cell (m, b, p) at rho_mm (position on the grid), or throws.
  std::array<double, 6> AtRho(int m, int b, int p, double rho_mm, bool clamp, Frame frame,
                              const std::string& what) const;

  std::string path_;
  std::vector<std::string> materials_;
  std::vector<int> material_ids_;
  std::vector<double> bite_depths_;  // [m]
  std::vector<int> passes_;
  std::vector<double> rho_;                               // [m]
  double rho_step_ = 0;                                   // [m]
  RhoDefinition rho_definition_ = RhoDefinition::kAlong;  // tables before 2026-12-06: along
  std::vector<double> force_body_, torque_body_, force_scoop_, torque_scoop_;  // M*B*P*R*3
  std::vector<double> rho_end_;                                                // M*B*P
};

}  // namespace sim
