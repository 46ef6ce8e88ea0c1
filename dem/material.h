// Particle and wall materials and the interaction parameters of each material pair.
// Public header of the dem module.
#pragma once

#include <string>
#include <vector>

namespace dem {

struct Material {
  std::string name;
  double density = 0;        // solid density [kg/m^3]
  double shear_modulus = 0;  // G [Pa]
  double poisson = 0;        // nu [-], in [0, 0.5)
  double YoungsModulus() const { return 2.0 * shear_modulus * (1.0 + poisson); }  // E = 2G(1+nu)
};

// How the rolling-friction torque is made (dem/contact.h gives each equation and its source).
enum class RollingModel : unsigned char {
  kEdem,    // "edem": EDEM's standard model, each particle against its own spin (the default)
  kCdt,     // "cdt": LIGGGHTS' constant directional torque, twist removed
  kLegacy,  // "legacy": scoopsim before issue 18, against the whole relative spin (twist too)
};
// How the normal damping is set from the restitution (dem/contact.h).
enum class DampingLaw : unsigned char {
  kStandard,  // "standard": beta = ln e / sqrt(ln^2 e + pi^2), as EDEM and LIGGGHTS (default)
  kExactRestitution,  // "exact_restitution": beta solved so that a Hertz impact has exactly e
};

// The names used in materials files ("edem", "cdt", "legacy"; "standard", "exact_restitution"),
// and back: false for an unknown name.
const char* Name(RollingModel model);
const char* Name(DampingLaw law);
bool ParseRollingModel(const std::string& name, RollingModel* model);
bool ParseDampingLaw(const std::string& name, DampingLaw* law);

// Parameters of the contact between two materials (symmetric in the pair).
struct Interaction {
  double restitution = 0.5;       // e in (0, 1]: v_out / v_in of a head-on binary collision
  double friction = 0.5;          // static friction coefficient mu_s >= 0 (Coulomb cap)
  double rolling_friction = 0.0;  // mu_r >= 0
  RollingModel rolling_model = RollingModel::kEdem;
  DampingLaw damping = DampingLaw::kStandard;
};

class MaterialTable {
 public:
  // Adds a material and returns its index; interactions with it default to Interaction{}.
  int Add(const Material& material);
  void SetInteraction(int a, int b, const Interaction& interaction);
  // Index of the named material, or -1.
  int Find(const std::string& name) const;
  int size() const { return static_cast<int>(materials_.size()); }
  const Material& operator[](int i) const { return materials_[i]; }
  const Interaction& interaction(int a, int b) const { return interactions_[a * size() + b]; }
  // True once SetInteraction was called for the pair.
  bool has_interaction(int a, int b) const { return defined_[a * size() + b] != 0; }

 private:
  std::vector<Material> materials_;
  std::vector<Interaction> interactions_;  // size() x size(), symmetric
  std::vector<char> defined_;              // size() x size()
};

// Rayleigh time step (paper eq. 4; Li et al. 2005 form):
// t_R = pi R sqrt(rho / G) / (0.1631 nu + 0.8766), R the smallest particle radius [s].
double RayleighTimeStep(double radius, const Material& material);

}  // namespace dem
