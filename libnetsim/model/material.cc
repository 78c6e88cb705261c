#include "libnetsim/model/material.h"

#include <cmath>
#include <sstream>

namespace netlab::netsim {

bool Material::IsValid(std::string* error) const {
  struct Field {
    const char* key;
    double value;
    bool may_be_zero;
  };
  const Field fields[] = {
      {"diameter", diameter, false},
      {"linear_density", linear_density, false},
      {"stretch_stiffness", stretch_stiffness, false},
      {"bend_stiffness", bend_stiffness, false},
      {"twist_stiffness", twist_stiffness, false},
      {"stretch_damping", stretch_damping, true},
      {"bend_damping", bend_damping, true},
      {"twist_damping", twist_damping, true},
  };
  for (const Field& f : fields) {
    const bool ok = std::isfinite(f.value) && (f.may_be_zero ? f.value >= 0.0 : f.value > 0.0);
    if (!ok) {
      if (error) {
        std::ostringstream os;
        os << f.key << " must be " << (f.may_be_zero ? ">= 0" : "> 0") << " (got " << f.value
           << ")";
        *error = os.str();
      }
      return false;
    }
  }
  return true;
}

}  // namespace netlab::netsim
