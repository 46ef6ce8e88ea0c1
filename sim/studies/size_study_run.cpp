// `scoopsim study particle-size`: the size study's cases as a sweep, then eq. 6-7 on what they
// wrote (sim/studies/size_study.h). Declared in sim/studies/commands.h.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/studies/commands.h"
#include "sim/input/exit_status.h"
#include "sim/loop/progress.h"
#include "sim/files/saved_run.h"
#include "sim/studies/size_study.h"
#include "sim/studies/sweep.h"

namespace sim {
namespace {

namespace fs = std::filesystem;
constexpr double kTolerancePct = 20;  // eq. 7

// Writes `text` to `path` unless it holds it already; a temporary file renamed into place, so
// that ranks of one mpirun writing the same text never leave a torn file.
void WriteIfChanged(const fs::path& path, const std::string& text) {
  std::stringstream old;
  if (std::ifstream in(path); in) old << in.rdbuf();
  if (old.str() == text) return;
  fs::create_directories(path.parent_path());
  const fs::path tmp = path.string() + "." + std::to_string(::getpid()) + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << text;
    if (!out.flush()) throw InputError(tmp.string() + ": cannot write there");
  }
  fs::rename(tmp, path);
}

// One case's curve and peaks, from its file.
struct CaseResult {
  SizeCase c;
  SizeCurve curve;
  double cpu_s = 0, bed_cpu_s = 0;
};

CaseResult ReadCase(const SizeCase& c, const std::string& dir, double window) {
  CaseResult r;
  r.c = c;
  const std::string path = (fs::path(dir) / "cases" / (c.name + ".h5")).string();
  const SavedRun run(path);
  r.curve = MakeSizeCurve(run.Scoop(), window);
  if (r.curve.time.empty())
    throw std::runtime_error(path + ": the scoop never touched the bed (no row with |F| > 0)");
  r.bed_cpu_s = run.RootNumber("sweep_bed_cpu_s", 0);
  r.cpu_s = run.RootNumber("sweep_cpu_s", 0) + r.bed_cpu_s;
  return r;
}

std::string Number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

}  // namespace

int RunSizeStudy(const std::string& scene_path, const SizeStudyOptions& options) {
  const Scene scene = LoadScene(scene_path);
  RefuseArmScene(scene, "study particle-size");
  const std::vector<double> sizes = options.sizes_mm.empty() ? StudySizesMm() : options.sizes_mm;
  if (!(options.smooth_s >= 0) || !std::isfinite(options.smooth_s)) {
    throw InputError("study particle-size", 0, "--smooth-s", "a window >= 0 [s]",
                     Number(options.smooth_s));
  }
  const std::vector<SizeCase> cases =
      SizeCases(scene, sizes, options.beds, options.priors.empty() ? 2 : 1);

  // Earlier runs' rows (--prior), read before any case runs: a size run here is taken from here,
  // otherwise from the first file that has it.
  std::vector<SizeRow> prior_rows;
  std::vector<std::string> prior_notes;
  {
    std::vector<double> taken = sizes;
    for (const std::string& file : options.priors) {
      std::string used;
      for (const SizeRow& r : ReadSizeRows(file, scene_path, options.smooth_s)) {
        if (std::find(taken.begin(), taken.end(), r.size_mm) != taken.end()) continue;
        taken.push_back(r.size_mm);
        prior_rows.push_back(r);
        used += (used.empty() ? "" : ",") + Number(r.size_mm);
      }
      if (!used.empty()) prior_notes.push_back("sizes_mm=" + used + " from " + file);
    }
    if (taken.size() < 2) {
      throw InputError("study particle-size", 0, "--sizes",
                       "at least two different diameters, with those of --prior", Number(sizes[0]));
    }
  }

  // The cases as a sweep file in DIR, run by the sweep machinery.
  std::error_code ec;
  if (fs::exists(options.dir, ec) && !fs::is_directory(options.dir, ec))
    throw InputError("-o " + options.dir + ": expected the study's output folder, got a file");
  // Its path absolute and normal: a case's scene text names the sweep file, and a finished case
  // is skipped only for the same text, so `-o out/x` and `-o ./out/x/` must name it alike.
  const fs::path sweep_file =
      fs::absolute(fs::path(options.dir) / "size_study.sweep.yaml").lexically_normal();
  WriteIfChanged(sweep_file,
                 SizeSweepText(fs::absolute(scene_path).lexically_normal().string(), cases));
  const Sweep sweep = LoadSweep(sweep_file.string());
  if (options.list) {
    std::fputs(SweepCaseList(sweep, options.dir).c_str(), stdout);
    return kExitOk;
  }
  SweepOptions sweep_options;
  sweep_options.dir = options.dir;
  sweep_options.threads = options.threads;
  sweep_options.quiet = options.quiet;
  sweep_options.only_case = options.only_case;
  sweep_options.checkpoint_every = options.checkpoint_every;
  sweep_options.build_table = false;
  bool complete = false;
  sweep_options.on_complete = [&complete] { complete = true; };
  const int status = RunSweep(sweep, sweep_options);
  if (status != kExitOk) return status;
  if (!complete) {
    if (options.only_case >= 0) {
      Status(
          "scoopsim: study particle-size: the analysis runs once every case is done (the "
          "command again without --case)\n");
    }
    return kExitOk;
  }

  // Every case's curve, smoothed, and its peaks.
  std::vector<CaseResult> results;
  std::vector<SizePeak> peaks;
  for (const SizeCase& c : cases) {
    results.push_back(ReadCase(c, options.dir, options.smooth_s));
    const CaseResult& r = results.back();
    peaks.push_back({c.size_mm, c.bed, r.curve.peak_force, r.curve.peak_torque, r.cpu_s});
  }
  std::vector<SizeRow> rows = SummarizeSizes(peaks, kTolerancePct);
  rows.insert(rows.end(), prior_rows.begin(), prior_rows.end());
  rows = ScoreSizes(std::move(rows), kTolerancePct);
  const double verdict = LargestWithin(rows, false);
  const double verdict_spread = LargestWithin(rows, true);
  const ToleranceCrossing crossing = CrossTolerance(rows, kTolerancePct);
  const auto mm = [](double d) { return std::isnan(d) ? std::string("none") : Number(d); };
  const SizeRow& ref = rows.front();
  const auto from_prior = [&](double d) {
    return std::find(sizes.begin(), sizes.end(), d) == sizes.end();
  };

  // DIR/size_study.csv
  const fs::path csv = fs::path(options.dir) / "size_study.csv";
  {
    std::ofstream out(csv, std::ios::trunc);
    const double half = options.smooth_s / 2;
    out << "# scoopsim study particle-size " << scene_path << " (scoopsim " << SCOOPSIM_VERSION
        << "): paper section 4, eq. 5-7\n"
        << "# cases: " << sweep_file.string() << ", " << options.beds
        << " bed(s) per size (bed.seed + bed - 1), the scene's solid volume in each\n"
        << "# curve: /scoop/ rows of pass 1 from first contact (the first row with |F| > 0); "
           "|F| = |force_world| [N], |T| = |torque_world| about the scoop CoM [N m]\n"
        << "# smoothing: centred moving mean over " << Number(options.smooth_s)
        << " s of time, S_i = mean{y_j : |t_j - t_i| <= " << Number(half)
        << " s}; at the ends over the rows there are (one-sided); peak = max S_i\n"
        << "# reference: the finest size, " << Number(ref.size_mm) << " mm (bed-mean peaks: |F| "
        << Number(ref.peak_force_mean) << " N, |T| " << Number(ref.peak_torque_mean) << " N m)\n"
        << "# eq. 6: mpe = (peak - peak_ref) / peak_ref x 100, signed; peak = the bed mean of the "
           "beds' peaks; mpe min/max: each bed's peak against peak_ref (the spread)\n"
        << "# eq. 7: the largest size d such that every size from the reference up to d has "
           "|mpe_force| and |mpe_torque| <= 20 (within_20 = 1); with the spread: every bed's "
           "too\n"
        << "# verdict: largest_within_20pct_mm=" << Number(verdict) << "\n"
        << "# verdict_spread: largest_within_20pct_all_beds_mm=" << Number(verdict_spread) << "\n"
        << "# crossing: mpe_20pct_mm=" << mm(crossing.mm) << " (force " << mm(crossing.force_mm)
        << ", torque " << mm(crossing.torque_mm)
        << "): where |mpe| reaches 20, linear in d between the last size within and the first "
           "beyond (bed means; none: within at every size run); the study's 3.5 mm lies between "
           "its sizes 3.25 and 4\n"
        << "# cpu_s_mean: CPU seconds of a case (pour + dig, all threads), mean over its beds\n";
    for (const std::string& n : prior_notes) {
      out << "# prior: " << n
          << " (its rows: peaks, beds, cost; MPE recomputed here; no curves in size_curves.csv)\n";
    }
    out << SizeCsvHeader() << "\n";
    for (const SizeRow& r : rows) out << SizeCsvLine(r) << "\n";
    if (!out.flush()) throw InputError(csv.string() + ": cannot write there");
  }
  // DIR/size_curves.csv
  const fs::path curves = fs::path(options.dir) / "size_curves.csv";
  {
    std::ofstream out(curves, std::ios::trunc);
    out << "# scoopsim study particle-size: every case's curve (time since first contact [s], "
           "rho [m], |F| [N], |T| [N m], smoothed over "
        << Number(options.smooth_s) << " s)\n"
        << "size_mm,bed,time,rho,force,torque,force_smooth,torque_smooth\n";
    char line[256];
    for (const CaseResult& r : results) {
      const SizeCurve& c = r.curve;
      for (size_t k = 0; k < c.time.size(); ++k) {
        std::snprintf(line, sizeof line, "%g,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", r.c.size_mm,
                      r.c.bed, c.time[k], c.rho[k], c.force[k], c.torque[k], c.force_smooth[k],
                      c.torque_smooth[k]);
        out << line;
      }
    }
    if (!out.flush()) throw InputError(curves.string() + ": cannot write there");
  }

  // The table.
  std::printf(
      "\nParticle-size study (eq. 6-7): peaks of |F| and |T| smoothed over %g s, MPE "
      "against %g mm; [min, max] over the beds\n\n",
      options.smooth_s, ref.size_mm);
  std::printf(
      "| d [mm] | beds | peak |F| [N] | MPE F [%%] | peak |T| [N m] | MPE T [%%] | "
      "within 20%% | CPU s/case |\n|---|---|---|---|---|---|---|---|\n");
  for (const SizeRow& r : rows) {
    const char* within = &r == &ref        ? "reference"
                         : !r.within       ? "no"
                         : r.within_spread ? "yes, every bed"
                                           : "yes (the mean; not every bed)";
    std::printf(
        "| %g%s | %d | %.4g [%.4g, %.4g] | %+.1f [%+.1f, %+.1f] | %.4g [%.4g, %.4g] | "
        "%+.1f [%+.1f, %+.1f] | %s | %.3g |\n",
        r.size_mm, from_prior(r.size_mm) ? " (prior)" : "", r.beds, r.peak_force_mean,
        r.peak_force_min, r.peak_force_max, r.mpe_force_pct, r.mpe_force_min_pct,
        r.mpe_force_max_pct, r.peak_torque_mean, r.peak_torque_min, r.peak_torque_max,
        r.mpe_torque_pct, r.mpe_torque_min_pct, r.mpe_torque_max_pct, within, r.cpu_s_mean);
  }
  std::printf(
      "\nverdict (eq. 7): largest size within 20%%: %g mm (every bed within: %g mm); the "
      "study found 3.5 mm\n",
      verdict, verdict_spread);
  std::printf(
      "where |MPE| reaches 20%% (linear in d between the sizes around it): %s mm (force %s, "
      "torque %s)\n",
      mm(crossing.mm).c_str(), mm(crossing.force_mm).c_str(), mm(crossing.torque_mm).c_str());
  for (const std::string& n : prior_notes) std::printf("prior: %s\n", n.c_str());
  std::printf("scoopsim: wrote %s, %s\n", csv.c_str(), curves.c_str());
  std::fflush(stdout);

  if (!options.plot) return kExitOk;
  return RunPlotScript("plot_size_study.py", {options.dir}) ? kExitOk : kExitFailure;
}

}  // namespace sim
