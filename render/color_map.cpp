#include "render/color_map.h"

#include <algorithm>
#include <cmath>

namespace render {
namespace {

// matplotlib viridis at t = 0, 1/8, ..., 1.
constexpr float kViridis[9][3] = {
    {0.267004f, 0.004874f, 0.329415f}, {0.278826f, 0.175490f, 0.483397f},
    {0.229739f, 0.322361f, 0.545706f}, {0.172719f, 0.448791f, 0.557885f},
    {0.127568f, 0.566949f, 0.550556f}, {0.157851f, 0.683765f, 0.501686f},
    {0.369214f, 0.788888f, 0.382914f}, {0.678489f, 0.863742f, 0.189503f},
    {0.993248f, 0.906157f, 0.143936f},
};

// Tableau-10 colours, distinct on screen and in print.
constexpr float kCategorical[8][3] = {
    {0.839f, 0.690f, 0.400f}, {0.306f, 0.475f, 0.655f}, {0.882f, 0.341f, 0.349f},
    {0.349f, 0.631f, 0.310f}, {0.690f, 0.478f, 0.631f}, {0.463f, 0.718f, 0.698f},
    {0.929f, 0.788f, 0.282f}, {0.612f, 0.459f, 0.373f},
};

}  // namespace

bool ParseColorField(const std::string& name, ColorField* field) {
  for (ColorField f : {ColorField::kSpeed, ColorField::kDepth, ColorField::kMaterial,
                       ColorField::kForce, ColorField::kBrokenBonds}) {
    if (name == FieldName(f)) {
      *field = f;
      return true;
    }
  }
  return false;
}

const char* FieldName(ColorField field) {
  switch (field) {
    case ColorField::kSpeed:
      return "speed";
    case ColorField::kDepth:
      return "depth";
    case ColorField::kMaterial:
      return "material";
    case ColorField::kForce:
      return "force";
    case ColorField::kBrokenBonds:
      return "broken_bonds";
  }
  return "?";
}

const char* FieldUnit(ColorField field) {
  switch (field) {
    case ColorField::kSpeed:
      return "m/s";
    case ColorField::kDepth:
      return "m";
    case ColorField::kMaterial:
      return "";
    case ColorField::kForce:
      return "N";
    case ColorField::kBrokenBonds:
      return "";
  }
  return "";
}

Rgb Viridis(double t) {
  if (!(t > 0)) t = 0;  // also NaN
  if (t > 1) t = 1;
  const double s = t * 8;
  const int k = std::min(static_cast<int>(s), 7);
  const float u = static_cast<float>(s - k);
  const float* a = kViridis[k];
  const float* b = kViridis[k + 1];
  return {a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1]), a[2] + u * (b[2] - a[2])};
}

Rgb MaterialColor(int material) {
  const float* c = kCategorical[((material % 8) + 8) % 8];
  return {c[0], c[1], c[2]};
}

void ComputeField(const sim::WorldView& view, ColorField field, std::vector<float>* values) {
  values->clear();
  if (view.particles == nullptr) return;
  const dem::Particles& p = *view.particles;
  const size_t n = p.size();
  values->resize(n);
  float* out = values->data();
  switch (field) {
    case ColorField::kSpeed:
      for (size_t i = 0; i < n; ++i) out[i] = static_cast<float>(dem::Norm(p.v[i]));
      break;
    case ColorField::kDepth: {
      double top = -1e300;
      for (size_t i = 0; i < n; ++i) top = std::max(top, p.x[i].z);
      for (size_t i = 0; i < n; ++i) out[i] = static_cast<float>(top - p.x[i].z);
      break;
    }
    case ColorField::kMaterial:
      for (size_t i = 0; i < n; ++i) out[i] = static_cast<float>(p.material[i]);
      break;
    case ColorField::kForce: {
      // Snapshots read back from a file carry no forces (f empty): the field is then 0.
      const bool has_force = p.f.size() == n;
      const bool has_mass = p.mass.size() == n;
      for (size_t i = 0; i < n; ++i) {
        if (!has_force) {
          out[i] = 0;
          continue;
        }
        const dem::Vec3 weight = has_mass ? p.mass[i] * view.gravity : dem::Vec3{};
        out[i] = static_cast<float>(dem::Norm(p.f[i] - weight));
      }
      break;
    }
    case ColorField::kBrokenBonds: {
      const bool has = view.broken_bonds.size() == n;
      for (size_t i = 0; i < n; ++i) out[i] = has ? view.broken_bonds[i] : 0.0f;
      break;
    }
  }
}

void AutoRange::Update(ColorField field, const std::vector<float>& values) {
  if (values.empty()) return;
  if (field == ColorField::kMaterial) {
    const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
    min_ = std::min(min_, static_cast<double>(*lo));
    max_ = std::max(max_, static_cast<double>(*hi));
    return;
  }
  if (field == ColorField::kBrokenBonds) {
    // Counts: most particles have none, so the top, not a percentile.
    min_ = 0;
    max_ =
        std::max({max_, static_cast<double>(*std::max_element(values.begin(), values.end())), 1.0});
    return;
  }
  // 99th percentile: a few fast outliers would otherwise squash every other colour.
  std::vector<float> scratch(values);
  const size_t k = std::min(scratch.size() - 1, scratch.size() * 99 / 100);
  std::nth_element(scratch.begin(), scratch.begin() + static_cast<std::ptrdiff_t>(k),
                   scratch.end());
  const double floor =
      field == ColorField::kSpeed ? 1e-3 : (field == ColorField::kForce ? 1e-6 : 1e-3);
  min_ = 0;
  max_ = std::max({max_, static_cast<double>(scratch[k]), floor});
}

void SceneColorRange(const sim::Scene& scene, ColorField field, double* min, double* max) {
  const double h = scene.box_max.z - scene.box_min.z;
  const double g = dem::Norm(scene.gravity);
  *min = 0;
  switch (field) {
    case ColorField::kSpeed: {
      if (!scene.dig.enabled) {
        *max = std::sqrt(g * h);
        break;
      }
      const sim::TrajectorySpec& path = scene.dig.trajectory;
      double top = 0;
      for (const sim::Move& move : path.moves) {
        if (move.kind == sim::Move::Kind::kTranslate) top = std::max(top, move.speed);
        if (move.kind != sim::Move::Kind::kRotate) continue;
        const dem::Vec3 point = move.about_pivot ? path.pivot_offset : move.point;
        double lever = 0;
        for (const dem::Vec3& v : scene.dig.scoop.geometry.vertices)
          lever = std::max(lever, dem::Norm(v - point));
        top = std::max(top, move.speed * lever);
      }
      *max = top;
      break;
    }
    case ColorField::kDepth:
      *max = h;
      break;
    case ColorField::kMaterial:
      *max = std::max(0, scene.materials.size() - 1);
      break;
    case ColorField::kForce: {
      const int m = scene.materials.Find(scene.bed.material);
      const double r = scene.bed.radius_max;
      const double mass =
          m >= 0 ? scene.materials[m].density * 4.0 / 3.0 * 3.14159265358979 * r * r * r : 0.0;
      *max = r > 0 ? mass * g * h / (2 * r) : 0.0;
      break;
    }
    case ColorField::kBrokenBonds:
      *max = 6;
      break;
  }
  if (!(*max > *min)) *max = *min + 1;  // a degenerate scene: any non-empty range
}

}  // namespace render
