// OpenGL 3.3 core entry points for the app. Mesa's libGL exports every core function,
// so prototypes are enough: no loader library is needed.
#pragma once

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/gl.h>
#include <GL/glext.h>
