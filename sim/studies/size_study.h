// The particle-size study (paper section 4, eq. 5-7, Fig. 3-6) as pure functions: its cases (one
// per diameter and bed, the same solid volume for each), the smoothing of a dig's |F| and |T|,
// the maximum percent error of each size against the finest (eq. 6) and the largest size within
// the tolerance (eq. 7). `scoopsim study particle-size` (sim/studies/commands.h) runs the cases as a
// sweep (sim/studies/sweep.h) and calls these on what they wrote.
//
// Definitions (each tested against itself in tests/sim/size_study_test.cpp):
// - A case's curve: the /scoop/ rows of pass 1 from the first row with |F| > 0 (first contact)
//   on; |F| = |force_world|, |T| = |torque_world| (about the scoop's CoM; a norm, so any frame);
//   rho as the rows store it (the CoM's displacement along the trench since first contact).
// - Smoothing: a centred moving mean over a fixed window of time, S_i = mean{ y_j : |t_j - t_i|
//   <= w/2 } (1e-9 s slack). At the ends the window holds only the rows there are (no padding),
//   so it is one-sided there. Time, not rho: the rows are evenly spaced in time, while rho stalls
//   in the plunge and in the rotations (a rho window would average a whole plunge into one value);
//   the study's own Fig. 4 is plotted against time.
// - Peak: the largest smoothed value of a case's curve.
// - Eq. 6, signed: MPE(Sd) = (peak(Sd) - peak(ref)) / peak(ref) x 100, ref = the finest size
//   (its MPE is 0). Signed as the study's Fig. 6 plots it (a variation; coarser beds give more
//   force); the tolerance is applied to |MPE|. With several beds: peak(Sd) is the mean of the
//   beds' peaks, and the spread is min and max over Sd's beds of MPE(bed's peak) against the
//   reference's bed-mean peak.
// - Eq. 7: the largest size d such that every size from the finest up to d is within the
//   tolerance for force and torque (|MPE| <= 20%): the sizes that have converged, so that one
//   coarse size passing by chance above a failing one does not make the verdict. With the spread:
//   the same with every bed of each size (above the reference) within the tolerance.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/files/saved_run.h"
#include "sim/input/scene.h"

namespace sim {

// The study's diameters S (eq. 5) [mm].
std::vector<double> StudySizesMm();

// One case of the study: a diameter and a bed.
struct SizeCase {
  double size_mm = 0;  // diameter [mm]
  int bed = 1;         // 1-based
  std::string name;    // "d<size>_b<bed>", e.g. d8.25_b2 (the sweep's case name)
  double radius = 0;   // [m] = size_mm / 2000
  int64_t count = 0;   // spheres: the scene's count x (d0 / d)^3, rounded (the same solid volume)
  uint64_t seed = 0;   // the scene's bed.seed + bed - 1 (bed 1 is the scene's own bed)
  double skin = 0;     // [m] the scene's neighbor.skin x d / d0; 0 when the scene gives none
                       // (its default, a quarter diameter, then scales by itself)
};

// The cases, size by size in the order given, beds 1..beds within each. The base scene must be
// one of spheres of one radius d0 (bed.radius a number, no clump), poured (no bed.file), with a
// dig of one pass. Throws InputError naming the scene and key (or the option: --sizes, --beds)
// and what was expected.
// `min_sizes`: how many sizes --sizes must give (2; 1 when earlier runs' rows join the study).
std::vector<SizeCase> SizeCases(const Scene& base, const std::vector<double>& sizes_mm, int beds,
                                size_t min_sizes = 2);

// The sweep file (sim/studies/sweep.h) of these cases over the scene file `scene_path` (absolute, or
// relative to the sweep file's folder): a `cases:` list setting bed.radius, bed.count, bed.seed
// and (when the scene gives it) neighbor.skin.
std::string SizeSweepText(const std::string& scene_path, const std::vector<SizeCase>& cases);

// S_i = mean{ y_j : |t_j - t_i| <= window/2 + 1e-9 } for t ascending (see above). window >= 0.
std::vector<double> CentredMovingMean(const std::vector<double>& t, const std::vector<double>& y,
                                      double window);

// A case's curve after first contact (see above), smoothed over `window` seconds.
struct SizeCurve {
  std::vector<double> time;                         // since first contact [s] (n)
  std::vector<double> rho;                          // [m] (n)
  std::vector<double> force;                        // |F| [N] (n)
  std::vector<double> torque;                       // |T| [N m] (n)
  std::vector<double> force_smooth, torque_smooth;  // (n)
  double peak_force = 0;   // max of force_smooth [N] (0 when the scoop touched nothing)
  double peak_torque = 0;  // max of torque_smooth [N m]
};
SizeCurve MakeSizeCurve(const ScoopSeries& series, double window);

// Eq. 6: (value - reference) / reference x 100 [%].
double PercentError(double value, double reference);

// One case's peaks and cost.
struct SizePeak {
  double size_mm = 0;
  int bed = 1;
  double peak_force = 0;   // [N]
  double peak_torque = 0;  // [N m]
  double cpu_s = 0;        // pour + dig, all threads [s]
};

// One row of DIR/size_study.csv: one size, over its beds.
struct SizeRow {
  double size_mm = 0;
  int beds = 0;
  double peak_force_mean = 0, peak_force_min = 0, peak_force_max = 0;
  double mpe_force_pct = 0, mpe_force_min_pct = 0, mpe_force_max_pct = 0;
  double peak_torque_mean = 0, peak_torque_min = 0, peak_torque_max = 0;
  double mpe_torque_pct = 0, mpe_torque_min_pct = 0, mpe_torque_max_pct = 0;
  bool within = false;         // |mpe_force_pct| and |mpe_torque_pct| <= tolerance
  bool within_spread = false;  // so is every bed's (min and max); the reference: true
  double cpu_s_mean = 0;
};

// The rows, by ascending size; the reference is the smallest size. Throws std::invalid_argument
// for no peaks or a reference peak that is not > 0. = ScoreSizes(the peaks' per-size rows).
std::vector<SizeRow> SummarizeSizes(const std::vector<SizePeak>& peaks, double tolerance_pct);

// Eq. 6 and the tolerance on rows whose peaks (beds, mean, min, max) and cost are set: sorted by
// ascending size, every MPE and within flag set against the smallest size's bed means. So rows of
// earlier runs (ReadSizeRows) and this run's join the study as if their peaks were summarized
// together: each row keeps its own beds' mean and spread. Throws std::invalid_argument for no
// rows, a size twice, or a reference peak that is not > 0.
std::vector<SizeRow> ScoreSizes(std::vector<SizeRow> rows, double tolerance_pct);

// The rows of an earlier run's DIR/size_study.csv (`--prior FILE`), their peaks, beds and cost
// (its MPEs are recomputed here, against whatever is finest now). The file must be one of the
// same study: its first line names a scene with the same file name as `scene_path`, its
// smoothing line the same window `smooth_s` [s]; its header line is SizeCsvHeader(); each row
// has beds >= 1 and finite peaks with 0 < min <= mean <= max (1e-9 relative slack), and no
// size comes twice. Anything else throws InputError naming the file, the line, the column and
// what was expected.
std::vector<SizeRow> ReadSizeRows(const std::string& path, const std::string& scene_path,
                                  double smooth_s);

// Eq. 7 (see above) over rows by ascending size: the largest size within the tolerance, by the
// bed means (spread false) or by every bed (spread true). The reference always counts.
double LargestWithin(const std::vector<SizeRow>& rows, bool spread);

// Where |MPE| reaches the tolerance between the sizes run, for force and for torque: the first
// size (from the reference up) with |MPE| above the tolerance, d1, and the size before it, d0,
// give d* = d0 + (tol - |MPE(d0)|) / (|MPE(d1)| - |MPE(d0)|) x (d1 - d0), |MPE| linear in d
// between them (bed means). NaN for a quantity that is within at every size run. `mm` is the
// smaller of the two: the largest diameter within for both, on that line. It is >= eq. 7's
// verdict and below the next size run. The study's 3.5 mm is not one of its sizes S (eq. 5): it
// lies between its 3.25 and 4 mm, a point of this kind.
struct ToleranceCrossing {
  double force_mm = 0, torque_mm = 0, mm = 0;
};
ToleranceCrossing CrossTolerance(const std::vector<SizeRow>& rows, double tolerance_pct);

// The CSV's header line (no newline): size_mm,beds,peak_force_mean,...,within_20,cpu_s_mean.
std::string SizeCsvHeader();
// One CSV line of a row (no newline).
std::string SizeCsvLine(const SizeRow& row);

}  // namespace sim
