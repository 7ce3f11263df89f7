// One colour per integration method, shared by every sample that compares methods.
#pragma once

#include "pba/draw.h"
#include "pba/integrate.h"

namespace pba::app {

/// The colour of `m` in trails, plots and legends.
inline Color MethodColor(Method m) {
  switch (m) {
    case Method::ExplicitEuler: return Color::hex(0xe5484d);      // red: gains energy
    case Method::SemiImplicitEuler: return Color::hex(0xffc53d);  // yellow
    case Method::PositionVerlet: return Color::hex(0x46a758);     // green
    case Method::VelocityVerlet: return Color::hex(0x00b8d9);     // cyan
    case Method::Rk4: return Color::hex(0x7c9cff);                // light blue
    case Method::ImplicitEuler: return Color::hex(0xd6409f);      // pink: loses energy
  }
  return colors::white;
}

}  // namespace pba::app
