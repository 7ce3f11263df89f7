// Shapes: names, construction and validation (the geometry lives in its own files).
#include "pba/collide/shape.h"

namespace pba {

std::string_view to_string(ShapeType t) {
  switch (t) {
    case ShapeType::Plane: return "plane";
    case ShapeType::Sphere: return "sphere";
    case ShapeType::Box: return "box";
    case ShapeType::Capsule: return "capsule";
    case ShapeType::Hull: return "hull";
    case ShapeType::Mesh: return "mesh";
    case ShapeType::Compound: return "compound";
  }
  return "unknown";
}

}  // namespace pba
