// pba collide (workbook chapter 5): the collision module every body type is a client of.
//
// Shapes and their geometry (collide/shape.h), the flat world-space collider of a tick
// (collide/collider.h) and the collision world that holds the colliders of a tick and
// answers point contacts for particles and soft bodies (collide/collision_world.h), and the
// world queries over it: rays, shape casts, overlaps, distances (collide/query.h).
// The broad and narrow phases join this header as they land. Nothing here knows of
// velocities beyond a surface's own motion, or of bodies: those are the clients.
#pragma once

#include "pba/collide/collider.h"
#include "pba/collide/collision_world.h"
#include "pba/collide/query.h"
#include "pba/collide/shape.h"
