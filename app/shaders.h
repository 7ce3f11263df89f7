// GLSL 3.30 sources of the renderer's programs.
#pragma once

namespace pba::app::shaders {

/// Lit instanced solids: per-instance position, scale, rotation quaternion and colour.
inline constexpr const char* kMeshVs = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_nrm;
layout(location = 2) in vec3 i_pos;
layout(location = 3) in vec3 i_scale;
layout(location = 4) in vec4 i_quat;
layout(location = 5) in vec4 i_color;
uniform mat4 u_view_proj;
out vec3 v_world;
out vec3 v_nrm;
out vec4 v_color;
vec3 qrot(vec4 q, vec3 v) { return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v); }
void main() {
  vec3 p = qrot(i_quat, a_pos * i_scale) + i_pos;
  vec3 s = max(abs(i_scale), vec3(1e-6));
  v_nrm = qrot(i_quat, a_nrm / s);
  v_world = p;
  v_color = i_color;
  gl_Position = u_view_proj * vec4(p, 1.0);
}
)";

inline constexpr const char* kMeshFs = R"(#version 330 core
in vec3 v_world;
in vec3 v_nrm;
in vec4 v_color;
uniform vec3 u_eye;
uniform vec3 u_key;
uniform vec3 u_fill;
out vec4 frag;
void main() {
  vec3 n = normalize(v_nrm);
  if (!gl_FrontFacing) n = -n;
  vec3 v = normalize(u_eye - v_world);
  // hemisphere ambient, a key light, a weak fill from the other side, Blinn highlight
  float hemi = 0.5 + 0.5 * n.y;
  vec3 ambient = mix(vec3(0.22, 0.21, 0.20), vec3(0.42, 0.45, 0.50), hemi);
  float key = max(dot(n, u_key), 0.0);
  float fill = max(dot(n, u_fill), 0.0);
  vec3 h = normalize(u_key + v);
  float spec = pow(max(dot(n, h), 0.0), 40.0) * 0.30;
  float rim = pow(1.0 - max(dot(n, v), 0.0), 3.0) * 0.12;
  vec3 c = v_color.rgb * (ambient + 0.72 * key + 0.22 * fill) + vec3(spec + rim);
  frag = vec4(c, v_color.a);
}
)";

/// Filled triangles: per-vertex position, normal and colour, lit by the solids' fragment
/// shader (kMeshFs, which flips the normal on back faces: two-sided)
inline constexpr const char* kTriangleVs = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_nrm;
layout(location = 2) in vec4 a_color;
uniform mat4 u_view_proj;
out vec3 v_world;
out vec3 v_nrm;
out vec4 v_color;
void main() {
  v_world = a_pos;
  v_nrm = a_nrm;
  v_color = a_color;
  gl_Position = u_view_proj * vec4(a_pos, 1.0);
}
)";

/// Screen-space thick lines: a geometry shader turns each segment into a quad.
inline constexpr const char* kLineVs = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec4 a_color;
layout(location = 2) in float a_width;
uniform mat4 u_view_proj;
out vec4 g_color;
out float g_width;
void main() {
  g_color = a_color;
  g_width = a_width;
  gl_Position = u_view_proj * vec4(a_pos, 1.0);
}
)";

inline constexpr const char* kLineGs = R"(#version 330 core
layout(lines) in;
layout(triangle_strip, max_vertices = 4) out;
in vec4 g_color[];
in float g_width[];
uniform vec2 u_viewport;
out vec4 f_color;
out float f_edge;
out float f_width;
void main() {
  vec4 p0 = gl_in[0].gl_Position;
  vec4 p1 = gl_in[1].gl_Position;
  // clip the segment against a plane just in front of the eye
  const float e = 1e-3;
  if (p0.w < e && p1.w < e) return;
  if (p0.w < e) p0 = mix(p0, p1, (e - p0.w) / (p1.w - p0.w));
  if (p1.w < e) p1 = mix(p1, p0, (e - p1.w) / (p0.w - p1.w));
  // direction and normal in pixels
  vec2 s0 = p0.xy / p0.w * u_viewport * 0.5;
  vec2 s1 = p1.xy / p1.w * u_viewport * 0.5;
  vec2 d = s1 - s0;
  float len = length(d);
  d = len > 1e-6 ? d / len : vec2(1.0, 0.0);
  vec2 n = vec2(-d.y, d.x);
  float w = max(g_width[0], 1.0) * 0.5 + 0.5;
  // extend the ends by half a width so polylines join without gaps
  vec2 ext = d * w * 0.7;
  vec2 to_ndc = 2.0 / u_viewport;
  vec2 o0a = (n * w - ext) * to_ndc, o0b = (-n * w - ext) * to_ndc;
  vec2 o1a = (n * w + ext) * to_ndc, o1b = (-n * w + ext) * to_ndc;
  f_width = w;
  f_color = g_color[0]; f_edge = 1.0;  gl_Position = vec4(p0.xy + o0a * p0.w, p0.zw); EmitVertex();
  f_color = g_color[0]; f_edge = -1.0; gl_Position = vec4(p0.xy + o0b * p0.w, p0.zw); EmitVertex();
  f_color = g_color[1]; f_edge = 1.0;  gl_Position = vec4(p1.xy + o1a * p1.w, p1.zw); EmitVertex();
  f_color = g_color[1]; f_edge = -1.0; gl_Position = vec4(p1.xy + o1b * p1.w, p1.zw); EmitVertex();
  EndPrimitive();
}
)";

inline constexpr const char* kLineFs = R"(#version 330 core
in vec4 f_color;
in float f_edge;
in float f_width;
out vec4 frag;
void main() {
  // fade the outermost pixel for a smooth edge
  float px = (1.0 - abs(f_edge)) * f_width;
  float a = clamp(px + 0.25, 0.0, 1.0);
  frag = vec4(f_color.rgb, f_color.a * a);
}
)";

/// Round screen-facing points with a slight shading.
inline constexpr const char* kPointVs = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec4 a_color;
layout(location = 2) in float a_size;
uniform mat4 u_view_proj;
out vec4 v_color;
void main() {
  v_color = a_color;
  gl_Position = u_view_proj * vec4(a_pos, 1.0);
  gl_PointSize = max(a_size, 1.0);
}
)";

inline constexpr const char* kPointFs = R"(#version 330 core
in vec4 v_color;
out vec4 frag;
void main() {
  vec2 q = gl_PointCoord * 2.0 - 1.0;
  float r2 = dot(q, q);
  if (r2 > 1.0) discard;
  float shade = 1.0 - 0.25 * r2;
  frag = vec4(v_color.rgb * shade, v_color.a);
}
)";

/// Full-screen vertical gradient drawn first.
inline constexpr const char* kSkyVs = R"(#version 330 core
out float v_t;
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  v_t = p.y * 0.5 + 0.5;
  gl_Position = vec4(p, 0.999, 1.0);
}
)";

inline constexpr const char* kSkyFs = R"(#version 330 core
in float v_t;
uniform vec3 u_top;
uniform vec3 u_bottom;
out vec4 frag;
void main() { frag = vec4(mix(u_bottom, u_top, clamp(v_t, 0.0, 1.0)), 1.0); }
)";

/// Ground plane y = 0 with an anti-aliased procedural grid that fades with distance.
inline constexpr const char* kGroundVs = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
uniform mat4 u_view_proj;
uniform float u_extent;
out vec3 v_world;
void main() {
  v_world = vec3(a_pos.x * u_extent, 0.0, a_pos.z * u_extent);
  gl_Position = u_view_proj * vec4(v_world, 1.0);
}
)";

inline constexpr const char* kGroundFs = R"(#version 330 core
in vec3 v_world;
uniform float u_spacing;
uniform float u_extent;
uniform vec3 u_eye;
out vec4 frag;
float grid(vec2 c, float s) {
  vec2 g = c / s;
  vec2 w = fwidth(g);
  vec2 l = abs(fract(g - 0.5) - 0.5) / max(w, vec2(1e-4));
  return 1.0 - min(min(l.x, l.y), 1.0);
}
void main() {
  vec2 c = v_world.xz;
  float minor = grid(c, u_spacing);
  float major = grid(c, u_spacing * 5.0);
  vec3 col = vec3(0.205, 0.215, 0.232);
  col = mix(col, vec3(0.255, 0.265, 0.285), minor * 0.8);
  col = mix(col, vec3(0.330, 0.340, 0.365), major);
  // faint coloured axes through the origin
  vec2 aw = fwidth(c) * 1.2;
  float ax = 1.0 - min(abs(c.y) / aw.y, 1.0);
  float az = 1.0 - min(abs(c.x) / aw.x, 1.0);
  col = mix(col, vec3(0.62, 0.30, 0.30), ax * 0.7);
  col = mix(col, vec3(0.30, 0.40, 0.66), az * 0.7);
  // fade out towards the rim of the ground
  float r = length(c) / u_extent;
  float a = 1.0 - smoothstep(0.55, 1.0, r);
  frag = vec4(col, a);
}
)";

/// Soft blob shadows: a radial falloff on a ground-level quad.
inline constexpr const char* kShadowVs = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 2) in vec3 i_pos;
layout(location = 3) in vec3 i_scale;
layout(location = 5) in vec4 i_color;
uniform mat4 u_view_proj;
out vec2 v_q;
out float v_a;
void main() {
  v_q = a_pos.xz;
  v_a = i_color.a;
  gl_Position = u_view_proj * vec4(i_pos + vec3(a_pos.x * i_scale.x, 0.0, a_pos.z * i_scale.z), 1.0);
}
)";

inline constexpr const char* kShadowFs = R"(#version 330 core
in vec2 v_q;
in float v_a;
out vec4 frag;
void main() {
  float r = length(v_q);
  float a = v_a * (1.0 - smoothstep(0.2, 1.0, r));
  frag = vec4(0.0, 0.0, 0.0, a);
}
)";

}  // namespace pba::app::shaders
