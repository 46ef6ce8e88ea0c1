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

const char* Name(RollingModel model) {
  switch (model) {
    case RollingModel::kEdem:
      return "edem";
    case RollingModel::kCdt:
      return "cdt";
    case RollingModel::kLegacy:
      return "legacy";
  }
  return "?";
}

const char* Name(DampingLaw law) {
  return law == DampingLaw::kStandard ? "standard" : "exact_restitution";
}

bool ParseRollingModel(const std::string& name, RollingModel* model) {
  for (RollingModel m : {RollingModel::kEdem, RollingModel::kCdt, RollingModel::kLegacy}) {
    if (name == Name(m)) {
      *model = m;
      return true;
    }
  }
  return false;
}

bool ParseDampingLaw(const std::string& name, DampingLaw* law) {
  for (DampingLaw d : {DampingLaw::kStandard, DampingLaw::kExactRestitution}) {
    if (name == Name(d)) {
      *law = d;
      return true;
    }
  }
  return false;
}

double RayleighTimeStep(double radius, const Material& material) {
  return M_PI * radius * std::sqrt(material.density / material.shear_modulus) /
         (0.1631 * material.poisson + 0.8766);
}

}  // namespace dem
