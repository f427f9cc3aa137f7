// The OSMesa back end: OpenGL (Mesa's llvmpipe, a 4.5 compatibility profile) into a memory
// buffer, supersampled and box-filtered down for anti-aliasing.
//
// The shaded style renders each frame in two passes:
//  1. a shadow map: the depth of every shadow caster (cloths, spheres, meshes) seen from the
//     key light, orthographic over the casters' bounding sphere, into a depth texture;
//  2. the picture, 4x multisampled: per-pixel lighting (hemisphere sky, key light, fill light)
//     with the key light's visibility read from the shadow map through percentage-closer
//     filtering; each plane drawn last as a square reaching past the far plane (which cuts it
//     along a straight horizon), with grid lines every metre and every 10 cm, fading into the
//     background with depth.
// The simple style is fixed-function lighting and a finite ground quad, without shadows,
// supersampled.
//
// llvmpipe runs every branch of a shader under masks, so a shader costs all its instructions on
// every pixel, early exits included: the shadow filter is four bilinear taps (a 4 x 4 texel
// footprint), which with multisampling keeps the shaded style within twice the simple one's cost.
#define GL_GLEXT_PROTOTYPES
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>

#include "drape/core/obstacle.h"
#include "drape/render/renderer.h"

namespace drape::render {
namespace {

using Mat4 = Eigen::Matrix4d;

// Colours (linear RGB): obstacles, ground, grid lines, background; the cloths' come from the Look.
constexpr float OBSTACLE[3] = {0.55f, 0.60f, 0.68f};
constexpr float GROUND[3] = {0.62f, 0.66f, 0.58f};
constexpr float BACKGROUND[3] = {0.93f, 0.95f, 0.98f};
// Sphere obstacles are drawn as UV spheres of this many bands.
constexpr int SPHERE_BANDS = 48;
// The view's near and far planes, in scene extents.
constexpr double NEAR_PLANE = 1e-3, FAR_PLANE = 100;
// Side of the square shadow map, in texels.
constexpr int SHADOW_MAP_SIZE = 2048;
// Radius of the shadow filter, in shadow map texels: the penumbra's width.
constexpr float SHADOW_SOFTNESS = 3.0f;
// Width of the wireframe's lines, in output pixels.
constexpr float WIRE_WIDTH = 0.8f;

// Triangles as flat arrays, three corners each: positions, normals and barycentric corners
// (for the wireframe).
struct Triangles {
  std::vector<float> position, normal, corner;

  void add(const Vec3& p, const Vec3& n, int k) {
    for (int a = 0; a < 3; ++a) {
      position.push_back(float(p[a]));
      normal.push_back(float(n[a]));
      corner.push_back(a == k ? 1.0f : 0.0f);
    }
  }
  void clear() { position.clear(), normal.clear(), corner.clear(); }
  void draw() const {
    if (position.empty()) return;
    glEnableClientState(GL_VERTEX_ARRAY);
    glEnableClientState(GL_NORMAL_ARRAY);
    glEnableClientState(GL_TEXTURE_COORD_ARRAY);
    glVertexPointer(3, GL_FLOAT, 0, position.data());
    glNormalPointer(GL_FLOAT, 0, normal.data());
    glTexCoordPointer(3, GL_FLOAT, 0, corner.data());
    glDrawArrays(GL_TRIANGLES, 0, GLsizei(position.size() / 3));
    glDisableClientState(GL_TEXTURE_COORD_ARRAY);
    glDisableClientState(GL_NORMAL_ARRAY);
    glDisableClientState(GL_VERTEX_ARRAY);
  }
};

// Triangles [first, first + count) of a mesh with smooth (area-weighted) vertex normals.
void add_mesh(Triangles& out, const std::vector<Vec3>& x, const std::vector<Triangle>& triangles, std::size_t first,
              std::size_t count) {
  std::vector<Vec3> n(x.size(), Vec3::Zero());
  for (std::size_t i = first; i < first + count; ++i) {
    const Triangle& t = triangles[i];
    const Vec3 face = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
    for (int k = 0; k < 3; ++k) n[t[k]] += face;
  }
  for (std::size_t i = first; i < first + count; ++i)
    for (int k = 0; k < 3; ++k) {
      const int v = triangles[i][k];
      out.add(x[v], n[v].norm() > 0 ? Vec3(n[v].normalized()) : Vec3::UnitZ(), k);
    }
}

void add_sphere(Triangles& out, const Vec3& c, Scalar r) {
  const auto point = [&](int i, int j) {
    const Scalar a = M_PI * i / SPHERE_BANDS, b = M_PI * j / SPHERE_BANDS;
    return Vec3(std::sin(a) * std::cos(b), std::sin(a) * std::sin(b), std::cos(a));
  };
  for (int i = 0; i < SPHERE_BANDS; ++i)
    for (int j = 0; j < 2 * SPHERE_BANDS; ++j) {
      const Vec3 n[4] = {point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)};
      for (const auto& [a, b, d] : {std::array{0, 1, 2}, std::array{0, 2, 3}})
        for (int k = 0; k < 3; ++k) {
          const Vec3& m = n[k == 0 ? a : k == 1 ? b : d];
          out.add(c + r * m, m, k);
        }
    }
}

Mat4 look_at(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 f = (target - eye).normalized(), s = f.cross(up).normalized(), u = s.cross(f);
  Mat4 m = Mat4::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye), m(1, 3) = -u.dot(eye), m(2, 3) = f.dot(eye);
  return m;
}

Mat4 frustum(double fov_degrees, double aspect, double near_plane, double far_plane) {
  const double top = near_plane * std::tan(fov_degrees * M_PI / 360.0), right = top * aspect;
  Mat4 m = Mat4::Zero();
  m(0, 0) = near_plane / right, m(1, 1) = near_plane / top;
  m(2, 2) = -(far_plane + near_plane) / (far_plane - near_plane), m(2, 3) = -2 * far_plane * near_plane / (far_plane - near_plane);
  m(3, 2) = -1;
  return m;
}

Mat4 ortho(double radius, double near_plane, double far_plane) {
  Mat4 m = Mat4::Identity();
  m(0, 0) = m(1, 1) = 1 / radius;
  m(2, 2) = -2 / (far_plane - near_plane), m(2, 3) = -(far_plane + near_plane) / (far_plane - near_plane);
  return m;
}

void load(GLenum mode, const Mat4& m) {
  glMatrixMode(mode);
  glLoadMatrixd(m.data());  // Eigen is column-major, as OpenGL
}

void uniform(GLuint program, const char* name, const Mat4& m) {
  const Eigen::Matrix4f f = m.cast<float>();
  glUniformMatrix4fv(glGetUniformLocation(program, name), 1, GL_FALSE, f.data());
}
void uniform(GLuint program, const char* name, const Vec3& v) {
  glUniform3f(glGetUniformLocation(program, name), float(v.x()), float(v.y()), float(v.z()));
}
void uniform(GLuint program, const char* name, const float* v) { glUniform3fv(glGetUniformLocation(program, name), 1, v); }
void uniform(GLuint program, const char* name, float v) { glUniform1f(glGetUniformLocation(program, name), v); }
void uniform(GLuint program, const char* name, int v) { glUniform1i(glGetUniformLocation(program, name), v); }

// Shared by both shaded programs: the lights and the key light's visibility from the shadow map.
constexpr const char* LIGHTING = R"(
uniform vec3 key_direction, fill_direction, up;
uniform sampler2DShadow shadow_map;
uniform mat4 light_matrix;    // world to shadow map texture coordinates and depth
uniform float shadow_texel;   // world size of one shadow map texel
uniform float softness;       // filter radius in texels
const vec2 TAPS[4] = vec2[](vec2(-0.75, -0.25), vec2(0.25, -0.75), vec2(0.75, 0.25), vec2(-0.25, 0.75));
float key_visibility(vec3 world, vec3 n) {
  // Offset along the normal by a texel and a half against self-shadowing of lit surfaces;
  // outside the map, lit.
  vec4 p = light_matrix * vec4(world + n * (1.5 * shadow_texel), 1.0);
  if (any(lessThan(p.xyz, vec3(0.0))) || any(greaterThan(p.xyz, vec3(1.0)))) return 1.0;
  float texel = 1.0 / float(textureSize(shadow_map, 0).x), lit = 0.0;
  for (int i = 0; i < 4; ++i) lit += texture(shadow_map, vec3(p.xy + TAPS[i] * softness * texel, p.z));
  return 0.25 * lit;
}
vec3 lit(vec3 albedo, vec3 world, vec3 n) {
  float sky = 0.5 + 0.5 * dot(n, up);
  vec3 ambient = mix(vec3(0.24, 0.24, 0.23), vec3(0.40, 0.41, 0.44), sky);
  float key = max(dot(n, key_direction), 0.0);
  if (key > 0.0) key *= key_visibility(world, n);
  float fill = max(dot(n, fill_direction), 0.0);
  return albedo * (ambient + key * vec3(0.72, 0.71, 0.66) + fill * vec3(0.20, 0.22, 0.25));
}
)";

constexpr const char* SURFACE_VERTEX = R"(#version 130
uniform mat4 view_projection;
out vec3 world, normal, corner;
void main() {
  world = gl_Vertex.xyz;
  normal = gl_Normal;
  corner = gl_MultiTexCoord0.xyz;
  gl_Position = view_projection * gl_Vertex;
}
)";

constexpr const char* SURFACE_FRAGMENT = R"(
in vec3 world, normal, corner;
uniform vec3 front_colour, back_colour;
uniform float wire_width;   // in pixels; 0: no wireframe
void main() {
  vec3 n = normalize(normal);
  vec3 albedo = front_colour;
  if (!gl_FrontFacing) n = -n, albedo = back_colour;
  vec3 colour = lit(albedo, world, n);
  if (wire_width > 0.0) {
    vec3 d = corner / fwidth(corner);
    float edge = min(min(d.x, d.y), d.z);
    colour = mix(colour * 0.35, colour, smoothstep(0.0, wire_width, edge));
  }
  gl_FragColor = vec4(colour, 1.0);
}
)";

constexpr const char* PLANE_VERTEX = R"(#version 130
uniform mat4 view_projection;
out vec3 world;
void main() {
  world = gl_Vertex.xyz;
  gl_Position = view_projection * gl_Vertex;
}
)";

constexpr const char* PLANE_FRAGMENT = R"(
in vec3 world;
uniform vec3 eye, forward, plane_point, plane_normal, axis_u, axis_v, ground, background;
uniform float fade_distance;
// Coverage of grid lines `spacing` apart, about a pixel wide, faded out where they crowd.
float grid(vec2 c, float spacing) {
  vec2 g = c / spacing, w = fwidth(g);
  vec2 line = abs(fract(g - 0.5) - 0.5) / max(w, 1e-6);
  float crowding = max(w.x, w.y);
  return (1.0 - min(min(line.x, line.y), 1.0)) * (1.0 - smoothstep(0.1, 0.3, crowding));
}
void main() {
  vec3 n = dot(eye - plane_point, plane_normal) > 0.0 ? plane_normal : -plane_normal;
  vec2 c = vec2(dot(world - plane_point, axis_u), dot(world - plane_point, axis_v));
  float lines = max(0.45 * grid(c, 1.0), 0.15 * grid(c, 0.1));
  vec3 colour = lit(ground * (1.0 - 0.35 * lines), world, n);
  // Haze by depth along the view, not by distance: its lines of equal strength on the plane
  // are parallel to the horizon, which stays straight at any field of view.
  float s = dot(world - eye, forward) / fade_distance;
  gl_FragColor = vec4(mix(colour, background, 1.0 - exp(-s * s)), 1.0);
}
)";

// Throws RenderError with OpenGL's log when a shader or program's status is false:
// get_status and get_log are glGetShaderiv and glGetShaderInfoLog, or the Program pair.
void require(GLuint object, GLenum status, void (*get_status)(GLuint, GLenum, GLint*),
             void (*get_log)(GLuint, GLsizei, GLsizei*, GLchar*), const char* what) {
  GLint ok = 0;
  get_status(object, status, &ok);
  if (ok) return;
  char log[2048] = {};
  get_log(object, sizeof log, nullptr, log);
  throw RenderError(std::string(what) + log);
}

GLuint compile(GLenum kind, const std::string& source) {
  const GLuint shader = glCreateShader(kind);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  require(shader, GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog, "a shader failed to compile: ");
  return shader;
}

GLuint link(const char* vertex, const std::string& fragment) {
  const GLuint program = glCreateProgram();
  glAttachShader(program, compile(GL_VERTEX_SHADER, vertex));
  glAttachShader(program, compile(GL_FRAGMENT_SHADER, "#version 130\n" + std::string(LIGHTING) + fragment));
  glLinkProgram(program);
  require(program, GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog, "a shader program failed to link: ");
  return program;
}

// A plane obstacle at time t: a point and the unit normal of its free side.
std::pair<Vec3, Vec3> posed_plane(const ObstacleSpec& s, Scalar t) {
  const Vec3 point = s.motion.position(s.point, t);
  return {point, (s.motion.position(s.point + s.normal, t) - point).normalized()};
}

class OsmesaRenderer final : public Renderer {
 public:
  OsmesaRenderer(int width, int height, int samples)
      : width_(width), height_(height), samples_(samples), buffer_(std::size_t(width) * samples * height * samples * 4) {
    context_ = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
    if (!context_) throw RenderError("OSMesa could not create a rendering context");
  }
  ~OsmesaRenderer() override { OSMesaDestroyContext(context_); }

  Image render(const Model& model, const std::vector<Vec3>& x, Scalar t, const Camera& camera, const Look& look) override {
    // The simple style supersamples by `samples` per axis; the shaded style shades each pixel
    // once with 4x multisampling (llvmpipe's most), supersampled by 2 per axis for 3 or 4.
    const int scale = look.style == Look::Style::Simple ? samples_ : (samples_ + 1) / 2;
    const int w = width_ * scale, h = height_ * scale;
    if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, w, h))
      throw RenderError("OSMesa could not make its context current");
    // Everything that casts a shadow: the obstacles' solids and the cloths, cloth by cloth.
    obstacles_.clear();
    for (const Obstacle& o : model.obstacles)
      if (o.spec.kind == ObstacleSpec::Kind::Sphere)
        add_sphere(obstacles_, o.spec.motion.position(o.spec.center, t), o.spec.radius);
      else if (o.spec.kind == ObstacleSpec::Kind::Mesh)
        add_mesh(obstacles_, posed_vertices(o, t), o.mesh.triangles, 0, o.mesh.triangles.size());
    cloths_.resize(model.cloths.size());
    for (std::size_t c = 0; c < model.cloths.size(); ++c) {
      cloths_[c].clear();
      add_mesh(cloths_[c], x, model.triangles, model.cloths[c].first_triangle, model.cloths[c].triangle_count);
    }

    const Vec3 view = (camera.target - camera.position).normalized();
    const Vec3 side = view.cross(camera.up).normalized();
    const Vec3 up = side.cross(view);
    const Scalar extent = scene_extent(model, x);
    const Mat4 view_matrix = look_at(camera.position, camera.target, up);
    const Mat4 projection = frustum(camera.fov_degrees, double(width_) / height_, extent * NEAR_PLANE, extent * FAR_PLANE);

    glEnable(GL_DEPTH_TEST);
    glClearColor(BACKGROUND[0], BACKGROUND[1], BACKGROUND[2], 1);
    if (look.style == Look::Style::Simple) {
      glViewport(0, 0, w, h);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
      render_simple(model, t, look, view, side, up, extent, view_matrix, projection);
    } else {
      render_shaded(model, t, look, camera, view, side, up, extent, view_matrix, projection, w, h, scale);
    }
    glFinish();
    return downsample(w, scale);
  }

 private:
  // The look before shadows: fixed-function two-sided lighting from a key and a fill light,
  // the planes as squares 20 scene extents wide.
  void render_simple(const Model& model, Scalar t, const Look& look, const Vec3& view, const Vec3& side, const Vec3& up,
                     Scalar extent, const Mat4& view_matrix, const Mat4& projection) {
    glUseProgram(0);
    load(GL_PROJECTION, projection);
    load(GL_MODELVIEW, view_matrix);
    glEnable(GL_NORMALIZE);
    glShadeModel(GL_SMOOTH);
    glEnable(GL_LIGHTING);
    glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
    const float ambient[4] = {0.30f, 0.30f, 0.32f, 1};
    glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
    const Vec3 key = (-view - 0.6 * side + 1.2 * up).normalized();
    const Vec3 fill = (-view + 0.8 * side + 0.3 * up).normalized();
    const float key_position[4] = {float(key.x()), float(key.y()), float(key.z()), 0};
    const float fill_position[4] = {float(fill.x()), float(fill.y()), float(fill.z()), 0};
    const float key_colour[4] = {0.75f, 0.74f, 0.70f, 1}, fill_colour[4] = {0.25f, 0.27f, 0.30f, 1};
    glEnable(GL_LIGHT0);
    glLightfv(GL_LIGHT0, GL_POSITION, key_position);
    glLightfv(GL_LIGHT0, GL_DIFFUSE, key_colour);
    glEnable(GL_LIGHT1);
    glLightfv(GL_LIGHT1, GL_POSITION, fill_position);
    glLightfv(GL_LIGHT1, GL_DIFFUSE, fill_colour);
    const auto material = [](GLenum face, const float* rgb) {
      const float rgba[4] = {rgb[0], rgb[1], rgb[2], 1};
      glMaterialfv(face, GL_AMBIENT_AND_DIFFUSE, rgba);
    };
    material(GL_FRONT_AND_BACK, GROUND);
    for (const Obstacle& o : model.obstacles)
      if (o.spec.kind == ObstacleSpec::Kind::Plane) {
        const auto [point, normal] = posed_plane(o.spec, t);
        const Vec3 u = normal.unitOrthogonal(), v = normal.cross(u);
        glBegin(GL_QUADS);
        glNormal3d(normal.x(), normal.y(), normal.z());
        for (const auto& [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
          const Vec3 p = point + extent * 20 * (a * u + b * v);
          glVertex3d(p.x(), p.y(), p.z());
        }
        glEnd();
      }
    material(GL_FRONT_AND_BACK, OBSTACLE);
    obstacles_.draw();
    for (std::size_t c = 0; c < cloths_.size(); ++c) {
      const ClothColours colours = look.cloth(c);
      material(GL_FRONT, colours.front.data());
      material(GL_BACK, colours.back.data());
      cloths_[c].draw();
    }
    glDisable(GL_LIGHTING);
    if (look.wireframe) {
      // The edges as dark lines over the lit faces, pulled towards the camera.
      glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
      glEnable(GL_POLYGON_OFFSET_LINE);
      glPolygonOffset(-1.0f, -1.0f);
      glLineWidth(float(samples_));  // a pixel wide once filtered down
      glColor3f(0.15f, 0.1f, 0.1f);
      for (const Triangles& cloth : cloths_) cloth.draw();
      glDisable(GL_POLYGON_OFFSET_LINE);
      glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    }
  }

  void render_shaded(const Model& model, Scalar t, const Look& look, const Camera& camera, const Vec3& view, const Vec3& side,
                     const Vec3& up, Scalar extent, const Mat4& view_matrix, const Mat4& projection, int w, int h, int scale) {
    if (!surface_program_) start_shaded(w, h);
    // The key light from high on the camera's left, so that shadows fall behind and to the
    // right of what casts them, in view; the fill from the right.
    const Vec3 key = (-0.45 * view - 0.55 * side + 1.6 * up).normalized();
    const Vec3 fill = (-view + 0.8 * side + 0.3 * up).normalized();

    // 1. The shadow map over the casters' bounding sphere.
    Vec3 lo = Vec3::Constant(std::numeric_limits<Scalar>::max()), hi = -lo;
    for (const Triangles* set : casters())
      for (std::size_t i = 0; i < set->position.size(); i += 3) {
        const Vec3 p(set->position[i], set->position[i + 1], set->position[i + 2]);
        lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
      }
    const Vec3 centre = 0.5 * (lo + hi);
    const Scalar radius = std::max<Scalar>(0.5 * (hi - lo).norm(), 1e-3) * 1.02;
    const Mat4 light_view = look_at(centre + 2 * radius * key, centre, key.unitOrthogonal());
    const Mat4 light_projection = ortho(radius, radius, 3 * radius);
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_framebuffer_);
    glViewport(0, 0, SHADOW_MAP_SIZE, SHADOW_MAP_SIZE);
    glClear(GL_DEPTH_BUFFER_BIT);
    glUseProgram(0);
    load(GL_PROJECTION, light_projection);
    load(GL_MODELVIEW, light_view);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(2.0f, 4.0f);
    for (const Triangles* set : casters()) set->draw();
    glDisable(GL_POLYGON_OFFSET_FILL);
    glBindFramebuffer(GL_FRAMEBUFFER, picture_framebuffer_);
    glViewport(0, 0, w, h);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

    // 2. The picture.
    Mat4 to_texture = Mat4::Identity();  // clip coordinates [-1, 1] to texture coordinates [0, 1]
    to_texture.topLeftCorner<3, 3>() *= 0.5;
    to_texture.topRightCorner<3, 1>().setConstant(0.5);
    const Mat4 light_matrix = to_texture * light_projection * light_view;
    const Mat4 view_projection = projection * view_matrix;
    glBindTexture(GL_TEXTURE_2D, shadow_texture_);
    for (const GLuint program : {plane_program_, surface_program_}) {
      glUseProgram(program);
      uniform(program, "key_direction", key);
      uniform(program, "fill_direction", fill);
      uniform(program, "up", up);
      uniform(program, "shadow_map", 0);
      uniform(program, "light_matrix", light_matrix);
      uniform(program, "shadow_texel", float(2 * radius / SHADOW_MAP_SIZE));
      uniform(program, "softness", SHADOW_SOFTNESS);
      uniform(program, "view_projection", view_projection);
    }

    glUseProgram(surface_program_);
    uniform(surface_program_, "front_colour", OBSTACLE);
    uniform(surface_program_, "back_colour", OBSTACLE);
    uniform(surface_program_, "wire_width", 0.0f);
    obstacles_.draw();
    for (std::size_t c = 0; c < cloths_.size(); ++c) {
      const ClothColours colours = look.cloth(c);
      uniform(surface_program_, "front_colour", colours.front.data());
      uniform(surface_program_, "back_colour", colours.back.data());
      uniform(surface_program_, "wire_width", look.wireframe ? float(WIRE_WIDTH * scale) : 0.0f);
      cloths_[c].draw();
    }
    // The planes last: what the solids hide of them is never shaded.
    glUseProgram(plane_program_);
    uniform(plane_program_, "eye", camera.position);
    uniform(plane_program_, "forward", view);
    uniform(plane_program_, "ground", GROUND);
    uniform(plane_program_, "background", BACKGROUND);
    // The ground fades into the background over a few dozen scene extents.
    uniform(plane_program_, "fade_distance", float(30 * extent + (camera.position - camera.target).norm()));
    for (const Obstacle& o : model.obstacles)
      if (o.spec.kind == ObstacleSpec::Kind::Plane) {
        const auto [point, normal] = posed_plane(o.spec, t);
        // Grid axes along the world's x and y where the plane allows it.
        Vec3 u = Vec3::UnitX() - Vec3::UnitX().dot(normal) * normal;
        if (u.norm() < 0.1) u = Vec3::UnitY() - Vec3::UnitY().dot(normal) * normal;
        u.normalize();
        uniform(plane_program_, "plane_point", point);
        uniform(plane_program_, "plane_normal", normal);
        uniform(plane_program_, "axis_u", u);
        uniform(plane_program_, "axis_v", Vec3(normal.cross(u)));
        // A square reaching past the far plane, which cuts it along a straight horizon.
        const Vec3 foot = camera.position - (camera.position - point).dot(normal) * normal;
        const Vec3 v = normal.cross(u);
        glBegin(GL_QUADS);
        for (const auto& [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
          const Vec3 p = foot + 2 * FAR_PLANE * extent * (a * u + b * v);
          glVertex3d(p.x(), p.y(), p.z());
        }
        glEnd();
      }

    glUseProgram(0);
    glBindTexture(GL_TEXTURE_2D, 0);
    // Resolves the multisampled picture into OSMesa's buffer.
    glBindFramebuffer(GL_READ_FRAMEBUFFER, picture_framebuffer_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
    glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }

  std::vector<const Triangles*> casters() const {
    std::vector<const Triangles*> all{&obstacles_};
    for (const Triangles& c : cloths_) all.push_back(&c);
    return all;
  }

  // The shaders, the shadow map's depth texture and framebuffer, and the multisampled
  // framebuffer of w x h pixels the picture is drawn in, made once per context.
  void start_shaded(int w, int h) {
    surface_program_ = link(SURFACE_VERTEX, SURFACE_FRAGMENT);
    plane_program_ = link(PLANE_VERTEX, PLANE_FRAGMENT);
    glGenTextures(1, &shadow_texture_);
    glBindTexture(GL_TEXTURE_2D, shadow_texture_);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, SHADOW_MAP_SIZE, SHADOW_MAP_SIZE, 0, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &shadow_framebuffer_);
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_framebuffer_);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_texture_, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glBindTexture(GL_TEXTURE_2D, 0);
    if (status != GL_FRAMEBUFFER_COMPLETE) throw RenderError("OpenGL could not make the shadow map's framebuffer");
    GLint most = 0;
    glGetIntegerv(GL_MAX_SAMPLES, &most);
    const int multisamples = samples_ > 1 ? std::min(4, int(most)) : 0;
    GLuint buffers[2];
    glGenRenderbuffers(2, buffers);
    glBindRenderbuffer(GL_RENDERBUFFER, buffers[0]);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, multisamples, GL_RGBA8, w, h);
    glBindRenderbuffer(GL_RENDERBUFFER, buffers[1]);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, multisamples, GL_DEPTH_COMPONENT24, w, h);
    glBindRenderbuffer(GL_RENDERBUFFER, 0);
    glGenFramebuffers(1, &picture_framebuffer_);
    glBindFramebuffer(GL_FRAMEBUFFER, picture_framebuffer_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, buffers[0]);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, buffers[1]);
    const GLenum picture_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (picture_status != GL_FRAMEBUFFER_COMPLETE) throw RenderError("OpenGL could not make the multisampled framebuffer");
  }

  static Scalar scene_extent(const Model& model, const std::vector<Vec3>& x) {
    Vec3 lo = x[0], hi = x[0];
    for (const Vec3& p : x) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    for (const Obstacle& o : model.obstacles)
      if (o.spec.kind == ObstacleSpec::Kind::Sphere) lo = lo.cwiseMin(o.spec.center), hi = hi.cwiseMax(o.spec.center);
    return std::max<Scalar>((hi - lo).norm(), 1e-3);
  }

  // Box filter of samples x samples, flipping OpenGL's bottom-up rows.
  Image downsample(int w, int samples) const {
    Image image;
    image.width = width_;
    image.height = height_;
    image.rgb.resize(std::size_t(width_) * height_ * 3);
    const int n = samples * samples;
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x)
        for (int c = 0; c < 3; ++c) {
          int sum = 0;
          for (int dy = 0; dy < samples; ++dy)
            for (int dx = 0; dx < samples; ++dx)
              sum += buffer_[(std::size_t(y * samples + dy) * w + (x * samples + dx)) * 4 + c];
          image.rgb[(std::size_t(height_ - 1 - y) * width_ + x) * 3 + c] = std::uint8_t((sum + n / 2) / n);
        }
    return image;
  }

  int width_, height_, samples_;
  std::vector<std::uint8_t> buffer_;
  OSMesaContext context_ = nullptr;
  Triangles obstacles_;
  std::vector<Triangles> cloths_;
  GLuint surface_program_ = 0, plane_program_ = 0, shadow_texture_ = 0, shadow_framebuffer_ = 0, picture_framebuffer_ = 0;
};

}  // namespace

std::unique_ptr<Renderer> make_renderer(int width, int height, int samples) {
  // DRAPE_NO_GL forbids GL contexts: the tests use it to show a run without --render never
  // makes one.
  if (std::getenv("DRAPE_NO_GL")) throw RenderError("DRAPE_NO_GL is set: no GL context may be created");
  return std::make_unique<OsmesaRenderer>(width, height, samples);
}

}  // namespace drape::render
