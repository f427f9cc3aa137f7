// The OSMesa back end: legacy fixed-function OpenGL into a memory buffer, two-sided lighting,
// supersampled and box-filtered down for anti-aliasing.
#include <GL/osmesa.h>
#include <GL/gl.h>

#include <cmath>
#include <cstdlib>

#include "drape/core/obstacle.h"
#include "drape/render/renderer.h"

namespace drape::render {
namespace {

// Colours (linear RGB): cloth front and back, obstacles, ground, background.
constexpr float CLOTH_FRONT[4] = {0.80f, 0.22f, 0.18f, 1};
constexpr float CLOTH_BACK[4] = {0.95f, 0.78f, 0.30f, 1};
constexpr float OBSTACLE[4] = {0.55f, 0.60f, 0.68f, 1};
constexpr float GROUND[4] = {0.62f, 0.66f, 0.58f, 1};
constexpr float BACKGROUND[3] = {0.93f, 0.95f, 0.98f};
// Sphere obstacles are drawn as UV spheres of this many bands.
constexpr int SPHERE_BANDS = 48;

std::vector<Vec3> vertex_normals(const std::vector<Vec3>& x, const std::vector<Triangle>& triangles) {
  std::vector<Vec3> n(x.size(), Vec3::Zero());
  for (const Triangle& t : triangles) {
    const Vec3 face = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);  // area weighted
    for (int k = 0; k < 3; ++k) n[t[k]] += face;
  }
  for (Vec3& v : n) v = v.norm() > 0 ? Vec3(v.normalized()) : Vec3::UnitZ();
  return n;
}

void draw_mesh(const std::vector<Vec3>& x, const std::vector<Triangle>& triangles) {
  const std::vector<Vec3> n = vertex_normals(x, triangles);
  glBegin(GL_TRIANGLES);
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k) {
      glNormal3d(n[t[k]].x(), n[t[k]].y(), n[t[k]].z());
      glVertex3d(x[t[k]].x(), x[t[k]].y(), x[t[k]].z());
    }
  glEnd();
}

void draw_sphere(const Vec3& c, Scalar r) {
  for (int i = 0; i < SPHERE_BANDS; ++i) {
    const Scalar a0 = M_PI * i / SPHERE_BANDS, a1 = M_PI * (i + 1) / SPHERE_BANDS;
    glBegin(GL_QUAD_STRIP);
    for (int j = 0; j <= 2 * SPHERE_BANDS; ++j) {
      const Scalar b = M_PI * j / SPHERE_BANDS;
      for (Scalar a : {a0, a1}) {
        const Vec3 n(std::sin(a) * std::cos(b), std::sin(a) * std::sin(b), std::cos(a));
        glNormal3d(n.x(), n.y(), n.z());
        glVertex3d(c.x() + r * n.x(), c.y() + r * n.y(), c.z() + r * n.z());
      }
    }
    glEnd();
  }
}

void draw_plane(const Vec3& point, const Vec3& normal, Scalar half_size) {
  const Vec3 u = normal.unitOrthogonal(), v = normal.cross(u);
  glBegin(GL_QUADS);
  glNormal3d(normal.x(), normal.y(), normal.z());
  for (const auto& [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
    const Vec3 p = point + half_size * (a * u + b * v);
    glVertex3d(p.x(), p.y(), p.z());
  }
  glEnd();
}

void look_at(const Camera& c, double aspect, double near_plane, double far_plane) {
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  const double top = near_plane * std::tan(c.fov_degrees * M_PI / 360.0);
  glFrustum(-top * aspect, top * aspect, -top, top, near_plane, far_plane);
  glMatrixMode(GL_MODELVIEW);
  const Vec3 f = (c.target - c.position).normalized();
  const Vec3 s = f.cross(c.up).normalized();
  const Vec3 u = s.cross(f);
  const double m[16] = {s.x(), u.x(), -f.x(), 0, s.y(), u.y(), -f.y(), 0, s.z(), u.z(), -f.z(), 0, 0, 0, 0, 1};
  glLoadMatrixd(m);
  glTranslated(-c.position.x(), -c.position.y(), -c.position.z());
}

class OsmesaRenderer final : public Renderer {
 public:
  OsmesaRenderer(int width, int height, int samples)
      : width_(width), height_(height), samples_(samples), buffer_(std::size_t(width) * samples * height * samples * 4) {
    context_ = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
    if (!context_) throw RenderError("OSMesa could not create a rendering context");
  }
  ~OsmesaRenderer() override { OSMesaDestroyContext(context_); }

  Image render(const Model& model, const std::vector<Vec3>& x, Scalar t, const Camera& camera) override {
    const int w = width_ * samples_, h = height_ * samples_;
    if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, w, h))
      throw RenderError("OSMesa could not make its context current");
    glViewport(0, 0, w, h);
    glClearColor(BACKGROUND[0], BACKGROUND[1], BACKGROUND[2], 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_NORMALIZE);
    glShadeModel(GL_SMOOTH);
    const Scalar extent = scene_extent(model, x);
    look_at(camera, double(width_) / height_, extent * 1e-3, extent * 100);

    // Soft lighting: a key light from the camera's upper left, a fill from the other side,
    // ambient sky.
    glEnable(GL_LIGHTING);
    glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, GL_TRUE);
    const float ambient[4] = {0.30f, 0.30f, 0.32f, 1};
    glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
    const Vec3 view = (camera.target - camera.position).normalized();
    const Vec3 side = view.cross(camera.up).normalized();
    const Vec3 key = (-view - 0.6 * side + 1.2 * camera.up).normalized();
    const Vec3 fill = (-view + 0.8 * side + 0.3 * camera.up).normalized();
    const float key_position[4] = {float(key.x()), float(key.y()), float(key.z()), 0};
    const float fill_position[4] = {float(fill.x()), float(fill.y()), float(fill.z()), 0};
    const float key_colour[4] = {0.75f, 0.74f, 0.70f, 1}, fill_colour[4] = {0.25f, 0.27f, 0.30f, 1};
    glEnable(GL_LIGHT0);
    glLightfv(GL_LIGHT0, GL_POSITION, key_position);
    glLightfv(GL_LIGHT0, GL_DIFFUSE, key_colour);
    glEnable(GL_LIGHT1);
    glLightfv(GL_LIGHT1, GL_POSITION, fill_position);
    glLightfv(GL_LIGHT1, GL_DIFFUSE, fill_colour);

    // Obstacles and the ground.
    for (const Obstacle& o : model.obstacles) {
      const ObstacleSpec& s = o.spec;
      if (s.kind == ObstacleSpec::Kind::Plane) {
        glMaterialfv(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE, GROUND);
        const Vec3 point = s.motion.position(s.point, t);
        const Vec3 normal = (s.motion.position(s.point + s.normal, t) - point).normalized();
        draw_plane(point, normal, extent * 20);
      } else if (s.kind == ObstacleSpec::Kind::Sphere) {
        glMaterialfv(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE, OBSTACLE);
        draw_sphere(s.motion.position(s.center, t), s.radius);
      } else {
        glMaterialfv(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE, OBSTACLE);
        draw_mesh(posed_vertices(o, t), o.mesh.triangles);
      }
    }
    // The cloth, front and back in their own colours.
    glMaterialfv(GL_FRONT, GL_AMBIENT_AND_DIFFUSE, CLOTH_FRONT);
    glMaterialfv(GL_BACK, GL_AMBIENT_AND_DIFFUSE, CLOTH_BACK);
    draw_mesh(x, model.triangles);
    glFinish();
    return downsample(w, h);
  }

 private:
  static Scalar scene_extent(const Model& model, const std::vector<Vec3>& x) {
    Vec3 lo = x[0], hi = x[0];
    for (const Vec3& p : x) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    for (const Obstacle& o : model.obstacles)
      if (o.spec.kind == ObstacleSpec::Kind::Sphere) lo = lo.cwiseMin(o.spec.center), hi = hi.cwiseMax(o.spec.center);
    return std::max<Scalar>((hi - lo).norm(), 1e-3);
  }

  // Box filter of samples x samples, flipping OpenGL's bottom-up rows.
  Image downsample(int w, int h) const {
    Image image;
    image.width = width_;
    image.height = height_;
    image.rgb.resize(std::size_t(width_) * height_ * 3);
    const int n = samples_ * samples_;
    for (int y = 0; y < height_; ++y)
      for (int x = 0; x < width_; ++x)
        for (int c = 0; c < 3; ++c) {
          int sum = 0;
          for (int dy = 0; dy < samples_; ++dy)
            for (int dx = 0; dx < samples_; ++dx)
              sum += buffer_[(std::size_t(y * samples_ + dy) * w + (x * samples_ + dx)) * 4 + c];
          image.rgb[(std::size_t(height_ - 1 - y) * width_ + x) * 3 + c] = std::uint8_t((sum + n / 2) / n);
        }
    (void)h;
    return image;
  }

  int width_, height_, samples_;
  std::vector<std::uint8_t> buffer_;
  OSMesaContext context_ = nullptr;
};

}  // namespace

std::unique_ptr<Renderer> make_renderer(int width, int height, int samples) {
  // DRAPE_NO_GL forbids GL contexts: the tests use it to show a run without --render never
  // makes one.
  if (std::getenv("DRAPE_NO_GL")) throw RenderError("DRAPE_NO_GL is set: no GL context may be created");
  return std::make_unique<OsmesaRenderer>(width, height, samples);
}

}  // namespace drape::render
