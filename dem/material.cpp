#include "dem/material.h"

#include <cmath>

namespace dem {

int MaterialTable::Add(const Material& material) {
  const int old_n = size();
  const int n = old_n + 1;
  std::vector<Interaction> interactions(n * n);
  std::vector<char> defined(n * n, 0);
  for (int a = 0; a < old_n; ++a) {
    for (int b = 0; b < old_n; ++b) {
      interactions[a * n + b] = interactions_[a * old_n + b];
      defined[a * n + b] = defined_[a * old_n + b];
    }
  }
  materials_.push_back(material);
  interactions_ = std::move(interactions);
  defined_ = std::move(defined);
  return old_n;
}

void MaterialTable::SetInteraction(int a, int b, const Interaction& interaction) {
  interactions_[a * size() + b] = interaction;
  interactions_[b * size() + a] = interaction;
  defined_[a * size() + b] = defined_[b * size() + a] = 1;
}

int MaterialTable::Find(const std::string& name) const {
  for (int i = 0; i < size(); ++i) {
    if (materials_[i].name == name) return i;
  }
  return -1;
}

double RayleighTimeStep(double radius, const Material& material) {
  return M_PI * radius * std::sqrt(material.density / material.shear_modulus) /
         (0.1631 * material.poisson + 0.8766);
}

}  // namespace dem
