// pbrt's named media ("preset"): measured absorption and reduced scattering
// coefficients (per mm) of Jensen et al. 2001 ("A Practical Model for
// Subsurface Light Transport") and Narasimhan et al. 2006 ("Acquiring
// Scattering Properties of Participating Media by Dilution"), as pbrt's
// GetMediumScatteringProperties lists them.
#pragma once

#include <string>

#include "core/math.h"

namespace ferry {

// False if `name` is not one of them.
bool mediumPreset(const std::string& name, Vec3f& sigmaA, Vec3f& sigmaS);

}  // namespace ferry
