// `scoopsim arm info URDF`: what was read from an arm's URDF, so that a user who swaps in another
// URDF sees at once what the simulator will use.
#pragma once

#include <cstdio>
#include <string>

namespace tools {

// Prints the parsed arm (joints, types, limits, damping, friction, masses, total mass) and the
// gravity torques at the named poses of arm::kLanderPoses (the zero pose only for an arm that
// is not six-jointed) under gravity `g` [m/s^2] along -z of the base. Throws
// arm::ArmModelError on a bad URDF.
void PrintArmInfo(const std::string& urdf, double g, std::FILE* out);

}  // namespace tools
