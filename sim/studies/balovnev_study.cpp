// `scoopsim study balovnev`: the scene's dig against Balovnev's model (sim/studies/balovnev.h) along the
// same path. Declared in sim/studies/commands.h.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/studies/balovnev.h"
#include "sim/loop/bed.h"
#include "sim/studies/commands.h"
#include "sim/loop/dig.h"
#include "sim/input/exit_status.h"
#include "sim/loop/progress.h"
#include "sim/files/saved_run.h"
#include "sim/loop/scoop_driver.h"
#include "sim/loop/world.h"

namespace sim {
namespace {

constexpr double kDeg = M_PI / 180;

double CpuNow() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// The blade's tip in the l_scoop frame: the mean of the mesh's vertices furthest along +x (the
// cutting edge's corners; the study's scoop: (0.0982, 0, 0.0814), 2 mm from FACTS's
// l_scoop_tip frame at (0.1, 0, 0.08)).
dem::Vec3 BladeTip(const dem::TriangleMesh& mesh) {
  double x_max = -std::numeric_limits<double>::infinity();
  for (const dem::Vec3& v : mesh.vertices) x_max = std::max(x_max, v.x);
  dem::Vec3 sum{0, 0, 0};
  int n = 0;
  for (const dem::Vec3& v : mesh.vertices)
    if (v.x >= x_max - 1e-6) {
      sum = sum + v;
      ++n;
    }
  return (1.0 / n) * sum;
}

// One row of the comparison.
struct Row {
  double time, rho, depth, dem_h, dem_down;
  BalovnevForce split, plugin, lander;  // textbook (A split, A_II alone), the lander's variant
};

}  // namespace

std::string BalovnevCsvPath(const std::string& output) {
  return std::filesystem::path(output).replace_extension(".balovnev.csv").string();
}
std::string BalovnevPngPath(const std::string& output) {
  return std::filesystem::path(output).replace_extension(".balovnev.png").string();
}

int RunBalovnevStudy(const Scene& scene_in, const BalovnevStudyOptions& options) {
  InstallStopHandlers();
  const std::string who = scene_in.path + ": study balovnev";
  if (!scene_in.dig.enabled) throw InputError(who + ": the scene needs a dig");
  RefuseArmScene(scene_in, "study balovnev");
  // The model's inputs are checked before any work (a placeholder unit weight: the bed's comes
  // later).
  {
    BalovnevSoil probe = options.soil;
    probe.unit_weight = 1;
    try {
      Balovnev(0.01, options.tool, probe, options.buried, BalovnevBranch::kSplit);
    } catch (const std::invalid_argument& e) {
      throw InputError(std::string("study balovnev: ") + e.what());
    }
  }
  // Pass 1 only: the surface measured before the dig is the one its blade cuts.
  Scene scene = scene_in;
  if (scene.dig.passes > 1) {
    Status("scoopsim: study balovnev: pass 1 of %d (the surface is measured before it)\n",
           scene.dig.passes);
    scene.dig.passes = 1;
  }
  RefuseOutputOverScene(options.output, scene);
  CheckOutputPath(options.output);
  const std::string csv_path = BalovnevCsvPath(options.output);
  CheckWritable(csv_path);

  // The dig, as `scoopsim run` makes it, with the bed's surface and solid fraction measured
  // between the bed and the dig (before a buried start takes particles out).
  const double r_max = scene.bed.radius_max;
  SurfaceMap surface_map;
  double solid_fraction = 0, bed_surface = 0, density = 0;
  const double cpu0 = CpuNow();
  const auto wall0 = std::chrono::steady_clock::now();
  {
    World world(scene, options.threads);
    world.OpenOutput(options.output);
    world.KeepPour(PourPath(options.output));
    if (!scene.bed.file.empty()) {
      world.LoadBed(scene.bed.file);
    } else {
      SettleReport r;
      const int status = world.Pour(options.quiet, &r);
      if (status != kExitOk) return status;
    }
    const dem::Particles& p = world.system().particles();
    if (p.size() == 0) throw InputError(who + ": the bed is empty");
    surface_map = MeasureSurfaceMap(p, scene.box_min, scene.box_max, 2 * r_max);
    // Solid fraction: the bed's central part, 4 radii in from the side walls, from the floor up
    // to two diameters under the mean surface (the loose top layer left out).
    const dem::Vec3 margin{4 * r_max, 4 * r_max, 0};
    bed_surface = BedSurface(p, scene.box_min + margin, scene.box_max - margin, 4 * r_max);
    dem::Vec3 lo = scene.box_min + margin, hi = scene.box_max - margin;
    hi.z = bed_surface - 4 * r_max;
    if (!(hi.z > lo.z + 2 * r_max))
      throw InputError(who + ": the bed is too shallow to measure its solid fraction");
    solid_fraction = SolidFraction(p, lo, hi);
    const int material = scene.materials.Find(scene.bed.material);
    density = scene.materials[material].density;
    world.StartDig(MakeScoopDriver(scene));
    RunControl control;
    control.quiet = options.quiet;
    const RunResult result = world.Run(control);
    if (result.exit_status != kExitOk) return result.exit_status;
  }
  const double dig_cpu = CpuNow() - cpu0;
  const double dig_wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();

  // Balovnev along the saved path: the blade tip's depth below the local surface at each row.
  const double g = dem::Norm(scene.gravity);
  const double rho_bulk = solid_fraction * density;
  BalovnevSoil soil = options.soil;
  soil.unit_weight = rho_bulk * g;
  const dem::Vec3 tip = BladeTip(scene.dig.scoop.geometry);
  const dem::Vec3 trench{std::cos(scene.dig.heading), std::sin(scene.dig.heading), 0.0};
  const SavedRun saved(options.output);
  const ScoopSeries series = saved.Scoop();
  const double t_dig = saved.RootNumber("start_time", 0.0);  // the dig's clock starts there
  std::vector<Row> rows;
  std::ofstream csv(csv_path);
  csv.precision(17);  // every double as written: the CSV is the study's data
  csv << "# scoopsim study balovnev: " << scene.path << "; dig " << options.output << "\n"
      << "# rho_bulk " << rho_bulk << " kg/m^3 (solid fraction " << solid_fraction
      << " x particle density " << density << "), g " << g << " m/s^2, gamma " << soil.unit_weight
      << " N/m^3, q " << soil.surcharge << " Pa, c " << soil.cohesion << " Pa, phi "
      << soil.friction_angle / kDeg << " deg, delta " << soil.tool_friction_angle / kDeg
      << " deg, beta " << options.tool.rake / kDeg << " deg, w " << options.tool.width << " m, b "
      << (options.buried ? 1 : 0) << "\n"
      << "# depth: the blade tip (" << tip.x << ", " << tip.y << ", " << tip.z
      << " in l_scoop) below the bed's surface before the dig (mean column top of the 3 x 3 "
         "columns of side "
      << 2 * r_max << " m around it), 0 above it\n"
      << "# dem_horizontal: -F_world . trench (against the motion); dem_down: -F_world.z; "
         "balovnev_*: the textbook model with the bed's gamma, A split at x* (FACTS 7), "
         "plugin_*: the same with A_II always; time since the dig began [s]; forces [N]\n"
      << "# lander_*: the OceanWATERS lander plugin's variant: rho_bulk "
      << BalovnevLanderConstants{}.bulk_density << " kg/m^3, g "
      << BalovnevLanderConstants{}.gravity << " m/s^2, q = g x "
      << BalovnevLanderConstants{}.surcharge_mass << " kg/m^2, b 0, A_II, "
      << "F_h <= " << BalovnevLanderConstants{}.max_horizontal
      << " N, F_v <= " << BalovnevLanderConstants{}.max_vertical << " N\n"
      << "time,pass,rho,tip_x,tip_y,tip_z,surface,depth,dem_horizontal,dem_down,"
         "balovnev_horizontal,balovnev_vertical,plugin_horizontal,plugin_vertical,"
         "lander_horizontal,lander_vertical\n";
  for (size_t k = 0; k < series.time.size(); ++k) {
    const dem::Vec3 t = dem::Apply(series.pose[k], tip);
    const double s = surface_map.Height(t.x, t.y);
    const double depth = std::isfinite(s) ? std::max(0.0, s - t.z) : 0.0;
    Row row{series.time[k] - t_dig,
            series.rho[k],
            depth,
            -dem::Dot(series.force_world[k], trench),
            -series.force_world[k].z,
            Balovnev(depth, options.tool, soil, options.buried, BalovnevBranch::kSplit),
            Balovnev(depth, options.tool, soil, options.buried, BalovnevBranch::kPlugin),
            BalovnevLander(depth, options.tool, soil)};
    csv << row.time << "," << series.pass[k] << "," << row.rho << "," << t.x << "," << t.y << ","
        << t.z << "," << s << "," << depth << "," << row.dem_h << "," << row.dem_down << ","
        << row.split.horizontal << "," << row.split.vertical << "," << row.plugin.horizontal << ","
        << row.plugin.vertical << "," << row.lander.horizontal << "," << row.lander.vertical
        << "\n";
    rows.push_back(row);
  }
  csv.close();
  if (!csv) throw std::runtime_error(csv_path + ": could not be written");

  // The table: the rows from the first to the last with the blade below the surface, in ten
  // equal spans of time, each the mean of its rows; then the mean over every row cut.
  size_t first = rows.size(), last = 0;
  for (size_t k = 0; k < rows.size(); ++k)
    if (rows[k].depth > 0) {
      first = std::min(first, k);
      last = k;
    }
  std::printf(
      "scoopsim: study balovnev: %s (pass 1; dig %.1f s CPU, %.1f s wall)\n"
      "  rho_bulk %.1f kg/m^3 (solid fraction %.3f x %.0f), g %.3g m/s^2, gamma %.1f N/m^3, "
      "q %.3g Pa, c %.3g Pa, phi %.1f deg, delta %.1f deg, beta %.1f deg, w %.4g m, b %d\n"
      "  depth: the blade tip below the bed's surface before the dig (3 x 3 columns of %.1f mm "
      "around it); DEM horizontal: against the motion; vertical: downward on the scoop\n",
      scene.path.c_str(), dig_cpu, dig_wall, rho_bulk, solid_fraction, density, g, soil.unit_weight,
      soil.surcharge, soil.cohesion, soil.friction_angle / kDeg, soil.tool_friction_angle / kDeg,
      options.tool.rake / kDeg, options.tool.width, options.buried ? 1 : 0, 2e3 * r_max);
  // The columns of the models shown: textbook (A split, and the plugin's A_II beside it) and
  // the lander plugin's variant.
  const bool tb = options.show_textbook, ld = options.show_lander;
  std::printf(
      "| t [s] | rho [mm] | depth [mm] | DEM F_h [N] |%s%s DEM F_v down [N] |%s%s\n",
      tb ? " textbook F_h [N] | textbook A_II F_h [N] |" : "", ld ? " lander F_h [N] |" : "",
      tb ? " textbook F_v [N] | textbook A_II F_v [N] |" : "", ld ? " lander F_v [N] |" : "");
  std::printf("| --- | --- | --- | --- |%s%s --- |%s%s\n", tb ? " --- | --- |" : "",
              ld ? " --- |" : "", tb ? " --- | --- |" : "", ld ? " --- |" : "");
  auto print = [tb, ld](const char* label, const std::vector<Row>& span) {
    Row m{};
    for (const Row& r : span) {
      m.time += r.time;
      m.rho += r.rho;
      m.depth += r.depth;
      m.dem_h += r.dem_h;
      m.dem_down += r.dem_down;
      m.split.horizontal += r.split.horizontal;
      m.split.vertical += r.split.vertical;
      m.plugin.horizontal += r.plugin.horizontal;
      m.plugin.vertical += r.plugin.vertical;
      m.lander.horizontal += r.lander.horizontal;
      m.lander.vertical += r.lander.vertical;
    }
    const double n = static_cast<double>(span.size());
    if (label != nullptr)
      std::printf("| %s ", label);
    else
      std::printf("| %.3f ", m.time / n);
    std::printf("| %.1f | %.1f | %.3g |", 1e3 * m.rho / n, 1e3 * m.depth / n, m.dem_h / n);
    if (tb) std::printf(" %.3g | %.3g |", m.split.horizontal / n, m.plugin.horizontal / n);
    if (ld) std::printf(" %.3g |", m.lander.horizontal / n);
    std::printf(" %.3g |", m.dem_down / n);
    if (tb) std::printf(" %.3g | %.3g |", m.split.vertical / n, m.plugin.vertical / n);
    if (ld) std::printf(" %.3g |", m.lander.vertical / n);
    std::printf("\n");
  };
  if (first <= last) {
    const double t0 = rows[first].time, t1 = rows[last].time;
    const int spans = 10;
    for (int s = 0; s < spans; ++s) {
      std::vector<Row> span;
      for (size_t k = first; k <= last; ++k) {
        const double u = (rows[k].time - t0) / std::max(t1 - t0, 1e-300);
        const int at = std::min(spans - 1, static_cast<int>(u * spans));
        if (at == s) span.push_back(rows[k]);
      }
      if (!span.empty()) print(nullptr, span);
    }
    std::vector<Row> cut;
    for (const Row& r : rows)
      if (r.depth > 0) cut.push_back(r);
    print("mean, rows cut", cut);
  } else {
    std::printf("| (the blade never went below the surface) |\n");
  }
  std::printf("scoopsim: wrote %s, %s\n", options.output.c_str(), csv_path.c_str());
  std::fflush(stdout);

  // The figure, by the project's plotting script.
  if (!options.plot) return kExitOk;
  const std::string png = BalovnevPngPath(options.output);
  const std::string model = tb && ld ? "both" : (tb ? "textbook" : "lander");
  return RunPlotScript("plot_balovnev.py", {csv_path, "-o", png, "--model", model}) ? kExitOk
                                                                                    : kExitFailure;
}

}  // namespace sim
