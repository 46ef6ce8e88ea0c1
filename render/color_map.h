// What colours the particles: a per-particle field (speed, depth, material, contact force) mapped
// through viridis (continuous fields) or a categorical palette (material). Public header.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/files/world_view.h"
#include "sim/input/scene.h"

namespace render {

enum class ColorField { kSpeed, kDepth, kMaterial, kForce, kBrokenBonds };

// "speed", "depth", "material", "force", "broken_bonds"; false when `name` is none of them.
bool ParseColorField(const std::string& name, ColorField* field);
const char* FieldName(ColorField field);
const char* FieldUnit(ColorField field);  // "m/s", "m", "", "N", ""

struct Rgb {
  float r = 0, g = 0, b = 0;  // linear 0..1, written to 8-bit as round(255 c)
};

// Viridis (matplotlib's default map), piecewise linear through its values at t = k/8, k = 0..8.
// t is clamped to [0, 1].
Rgb Viridis(double t);
// Categorical colour of material index m (cycles through 8 colours).
Rgb MaterialColor(int material);

// The field of every particle, in storage order (N):
//   speed     |v| [m/s]
//   depth     z_top - z [m], z_top the highest particle centre in the view (0 at the surface)
//   material  the material index
//   force     contact force |f - m g| [N] (f of the last step holds gravity; needs view.gravity)
//   broken_bonds  how many of the particle's bonds have broken (view.broken_bonds; 0 without)
void ComputeField(const sim::WorldView& view, ColorField field, std::vector<float>* values);

// A frame sequence has one colour range, fixed before its first frame, so that a colour means the
// same value in every frame (render/frames.h).

// The range of a saved run's sequence, from every frame's field before any is drawn: Update()
// with each snapshot's field, then [0, max] with max the largest 99th percentile seen (at least
// `floor`). Material ranges over the material indices seen, broken_bonds over [0, the most
// seen] (at least [0, 1]).
class AutoRange {
 public:
  void Update(ColorField field, const std::vector<float>& values);
  double min() const { return min_; }
  double max() const { return max_; }

 private:
  double min_ = 0, max_ = 0;
};

// The range of a running world's frames, fixed before the first (a run cannot see its later
// frames), from the scene:
//   speed     [0, the scoop's top speed on its path]: translations' speeds, rotations' rates
//             times the scoop mesh's farthest vertex from the rotation point (the speed of
//             grains the scoop carries); without a dig [0, sqrt(|g| h)], h the box's height
//   depth     [0, h]
//   material  [0, number of materials - 1]
//   force     [0, m |g| h / (2 r)]: the weight of a column of the bed's largest spheres (radius
//             r, mass m) filling the box's height (the force on the bottom layer at rest)
//   broken_bonds  [0, 6]: about the bonds a sphere of a settled bed has (its coordination number)
void SceneColorRange(const sim::Scene& scene, ColorField field, double* min, double* max);

}  // namespace render
