// Inputs shared by the tests of bad input (preflight_test.cpp, input_fuzz_test.cpp): a dig scene
// on tiny_dig's box and path, a bed for it laid out on a lattice (no pour: made in milliseconds),
// and an in-place edit of one value of a bed file.
#pragma once

#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sim/files/bed_io.h"
#include "sim/input/scene.h"
#include "sim/loop/world.h"

namespace scoopsim_test {

// tiny_dig's box, bed and path (scenes/tiny_dig.yaml), 8 mm snow spheres; `bed_file` ("" for
// none) is named relative to the scene's folder. Line numbers: 3 time_step, 5 box, 8 radius,
// 9 count, 10 file (when given); the dig's bite_depth and scoop lines follow.
inline std::string DigSceneText(const std::string& bed_file) {
  const std::string source = SCOOPSIM_SOURCE_DIR;
  return "materials: " + source + "/scenes/materials.yaml\n" +                   // 1
         "gravity: [0, 0, -1.3]\n"                                               // 2
         "time_step: {rayleigh_fraction: 0.25}\n"                                // 3
         "neighbor: {skin: 4.0e-3}\n"                                            // 4
         "box: {min: [0, 0, 0], max: [0.37, 0.17, 0.2], wall_material: wall}\n"  // 5
         "bed:\n"                                                                // 6
         "  material: snow\n"                                                    // 7
         "  radius: 8.0e-3\n"                                                    // 8
         "  count: 1450\n" +                                                     // 9
         (bed_file.empty() ? "" : "  file: " + bed_file + "\n") +                // 10
         "dig:\n"
         "  scoop: {mesh: " +
         source +
         "/assets/scoop.stl, material: aluminium}\n"
         "  trajectory:\n"
         "    preset: table1\n"
         "    start: [0.13, 0.085]\n"
         "    linear: {start: 3.0, speed: 0.3, distance: 0.05}\n"
         "    rotation2: {start: 3.2, rate: 90, angle: 90}\n"
         "  passes: 1\n"
         "  bite_depth: 0.02\n"
         "sleep: {enabled: true}\n";
}

inline void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

// A bed of `scene` laid out on a cubic lattice of touching 8 mm spheres, 23 x 10 x 6 (1380,
// surface at z = 0.096 m), saved to `bed_path` as `scoopsim bed` saves one.
inline void WriteLatticeBed(const std::string& scene_path, const std::string& bed_path) {
  const sim::Scene scene = sim::LoadScene(scene_path);
  sim::World world(scene, 1);
  dem::System& system = world.mutable_system();
  const int snow = scene.materials.Find("snow");
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 23; ++i)
        system.AddParticle({0.008 + 0.016 * i, 0.008 + 0.016 * j, 0.008 + 0.016 * k}, {}, {}, 0.008,
                           snow);
  sim::SaveBed(bed_path, system, scene.yaml_text);
}

// Sets element (row, column) of the double dataset `name` of an HDF5 file to `value`.
inline void SetBedValue(const std::string& path, const std::string& name, hsize_t row,
                        hsize_t column, double value) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  const hid_t dataset = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  const hid_t space = H5Dget_space(dataset);
  hsize_t dims[2] = {1, 1};
  const int rank = H5Sget_simple_extent_dims(space, dims, nullptr);
  std::vector<double> values(static_cast<size_t>(dims[0] * (rank > 1 ? dims[1] : 1)));
  H5Dread(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  values[static_cast<size_t>(row * (rank > 1 ? dims[1] : 1) + column)] = value;
  H5Dwrite(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Sclose(space);
  H5Dclose(dataset);
  H5Fclose(file);
}

}  // namespace scoopsim_test
