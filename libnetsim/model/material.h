#pragma once
// The material of a thread: the paper's 7 parameters (section 4.2) plus the diameter.
//
// Energies per unit length of rod (s the arc length, epsilon the axial strain, Omega the Darboux
// vector in the material frame, 1/m):
//   stretching  1/2 EA epsilon^2             damping  1/2 c_s  (d epsilon/dt)^2
//   bending     1/2 EI (Omega1^2 + Omega2^2)  damping  1/2 c_b  ((dOmega1/dt)^2 + (dOmega2/dt)^2)
//   torsion     1/2 GJ Omega3^2              damping  1/2 c_t  (dOmega3/dt)^2
// The dampings are the coefficients of the strain rates in Rayleigh dissipation potentials of the
// same form as the energies (Kelvin-Voigt): an axial strain rate of 1/s gives a damping force of
// c_s newtons, a curvature rate of 1/(m s) a damping moment of c_b newton metres.

#include <string>

namespace netlab::netsim {

struct Material {
  std::string name;
  double diameter = 0.0;           // m; drag reference width and contact radius (d/2)
  double linear_density = 0.0;     // kg/m
  double stretch_stiffness = 0.0;  // EA, N
  double bend_stiffness = 0.0;     // EI, N m^2
  double twist_stiffness = 0.0;    // GJ, N m^2
  double stretch_damping = 0.0;    // c_s, N s
  double bend_damping = 0.0;       // c_b, N m^2 s
  double twist_damping = 0.0;      // c_t, N m^2 s

  // True when every parameter is finite, the diameter, density and stiffnesses are > 0 and the
  // dampings >= 0. Otherwise false, with the first offending field named in *error.
  bool IsValid(std::string* error) const;
};

}  // namespace netlab::netsim
