#include "render/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/gl_api.h"  // gl.X and osmesa.X: the entry points, loaded at run time

namespace render {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Particles: one point per sphere. The vertex shader sizes the sprite to cover the sphere's
// silhouette; the fragment shader casts the pixel's view ray at the sphere, discards a miss, and
// writes the hit's colour and true depth, so spheres cut each other and the meshes exactly.
// Everything is in view space (camera at the origin looking down -z).
const char* kSphereVertex = R"(#version 330 core
layout(location = 0) in vec4 center_radius;  // world centre [m], radius [m]
layout(location = 1) in vec4 color;
uniform mat4 view;
uniform mat4 proj;
uniform float pixel_scale;  // pixels per unit of (size / distance) along y: height / 2 * proj[1][1]
flat out vec3 v_center;
flat out float v_radius;
flat out vec4 v_color;
void main() {
  vec4 c = view * vec4(center_radius.xyz, 1.0);
  float r = center_radius.w;
  v_center = c.xyz;
  v_radius = r;
  v_color = color;
  gl_Position = proj * c;
  float d = max(-c.z, 1e-9);
  // Half-size of the silhouette on axis is f r / sqrt(d^2 - r^2); off axis the silhouette is an
  // ellipse stretched by |c| / d along the radial direction. 2 px margin for rasterisation.
  float r_px = pixel_scale * r / sqrt(max(d * d - r * r, 1e-18));
  gl_PointSize = 2.0 * r_px * (length(c.xyz) / d) + 2.0;
}
)";

const char* kSphereFragment = R"(#version 330 core
flat in vec3 v_center;
flat in float v_radius;
flat in vec4 v_color;
uniform mat4 proj;
uniform vec2 viewport;  // [px]
uniform vec2 tan_half;  // tan of the half field of view along x and y
uniform int shading;
uniform vec3 light;     // unit vector, view space
uniform float ambient;
out vec4 frag_color;
void main() {
  vec2 ndc = gl_FragCoord.xy / viewport * 2.0 - 1.0;
  vec3 dir = normalize(vec3(ndc * tan_half, -1.0));
  // Closest approach of the ray to the centre, computed as a difference of nearby vectors so the
  // test stays accurate in single precision for millimetre spheres a metre away.
  float tc = dot(dir, v_center);
  vec3 perp = v_center - tc * dir;
  float d2 = dot(perp, perp);
  float r2 = v_radius * v_radius;
  if (d2 > r2) discard;
  float t = tc - sqrt(r2 - d2);
  vec3 hit = t * dir;
  vec4 clip = proj * vec4(hit, 1.0);
  gl_FragDepth = clip.z / clip.w * 0.5 + 0.5;
  vec3 n = (hit - v_center) / v_radius;
  float k = shading != 0 ? ambient + (1.0 - ambient) * max(dot(n, light), 0.0) : 1.0;
  frag_color = vec4(v_color.rgb * k, 1.0);
}
)";

// Meshes, ground and box edges: world-space triangles or lines with a normal, flat-lit.
const char* kSurfaceVertex = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
uniform mat4 view;
uniform mat4 proj;
out vec3 v_normal;
void main() {
  v_normal = mat3(view) * normal;
  gl_Position = proj * view * vec4(position, 1.0);
}
)";

const char* kSurfaceFragment = R"(#version 330 core
in vec3 v_normal;
uniform vec3 color;
uniform int lit;
uniform vec3 light;
uniform float ambient;
out vec4 frag_color;
void main() {
  float k = 1.0;
  if (lit != 0) {
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;  // two-sided: the inside of the scoop shows too
    k = ambient + (1.0 - ambient) * max(dot(n, light), 0.0);
  }
  frag_color = vec4(color * k, 1.0);
}
)";

struct SphereVertex {
  float x, y, z, radius;
  uint8_t rgba[4];
};
static_assert(sizeof(SphereVertex) == 20, "packed sphere vertex");

struct SurfaceVertex {
  float x, y, z, nx, ny, nz;
};

GLuint Compile(GLenum type, const char* source) {
  const GLuint shader = gl.CreateShader(type);
  gl.ShaderSource(shader, 1, &source, nullptr);
  gl.CompileShader(shader);
  GLint ok = 0;
  gl.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    gl.GetShaderInfoLog(shader, sizeof(log), nullptr, log);
    throw std::runtime_error(std::string("render: shader compile failed: ") + log);
  }
  return shader;
}

GLuint Link(const char* vertex, const char* fragment) {
  const GLuint vs = Compile(GL_VERTEX_SHADER, vertex);
  const GLuint fs = Compile(GL_FRAGMENT_SHADER, fragment);
  const GLuint program = gl.CreateProgram();
  gl.AttachShader(program, vs);
  gl.AttachShader(program, fs);
  gl.LinkProgram(program);
  gl.DeleteShader(vs);
  gl.DeleteShader(fs);
  GLint ok = 0;
  gl.GetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    gl.GetProgramInfoLog(program, sizeof(log), nullptr, log);
    throw std::runtime_error(std::string("render: shader link failed: ") + log);
  }
  return program;
}

std::array<float, 16> ToFloat(const Mat4& m) {
  std::array<float, 16> f{};
  for (int i = 0; i < 16; ++i) f[i] = static_cast<float>(m[i]);
  return f;
}

uint8_t To8(float c) {
  return static_cast<uint8_t>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f));
}

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

void AddTriangle(std::vector<SurfaceVertex>* out, const dem::Vec3& a, const dem::Vec3& b,
                 const dem::Vec3& c) {
  dem::Vec3 n = dem::Cross(b - a, c - a);
  const double len = dem::Norm(n);
  if (len > 0) n = (1.0 / len) * n;
  for (const dem::Vec3* p : {&a, &b, &c}) {
    out->push_back({static_cast<float>(p->x), static_cast<float>(p->y), static_cast<float>(p->z),
                    static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z)});
  }
}

}  // namespace

struct Renderer::Impl {
  OSMesaContext context = nullptr;
  Image image;
  const void* bound_buffer = nullptr;  // the buffer OSMesa renders into
  int bound_width = 0, bound_height = 0;
  GLuint sphere_program = 0, surface_program = 0;
  GLuint sphere_vao = 0, sphere_vbo = 0, surface_vao = 0, surface_vbo = 0;
  std::vector<SphereVertex> spheres;
  std::vector<SurfaceVertex> triangles, lines;
  std::vector<float> field;
  size_t sphere_capacity = 0;  // bytes allocated in sphere_vbo
  size_t drawn = 0;
  // Occlusion culling scratch (see Render): per particle its view depth and pixel footprint;
  // per cell the nearest covering sphere-centre depth.
  struct Footprint {
    float px, py;  // projected centre [px], y up
    float depth;   // view-space distance along the axis [m]
    float half;    // half side of the bounding square [px]
    float inner;   // half side of the inscribed square [px]
  };
  std::vector<Footprint> footprints;
  std::vector<float> cells;
  std::vector<float> blocks;  // farthest cell value of each 4 x 4 block
  std::vector<uint32_t> visible;

  void Bind(int width, int height) {
    if (image.width() != width || image.height() != height) image.Resize(width, height);
    if (bound_buffer == image.data() && bound_width == width && bound_height == height) return;
    if (!osmesa.MakeCurrent(context, image.data(), GL_UNSIGNED_BYTE, width, height)) {
      throw std::runtime_error("render: OSMesaMakeCurrent failed for " + std::to_string(width) +
                               "x" + std::to_string(height));
    }
    bound_buffer = image.data();
    bound_width = width;
    bound_height = height;
  }

  void DrawSurfaces(const std::vector<SurfaceVertex>& vertices, GLenum mode, float r, float g,
                    float b, bool lit) {
    if (vertices.empty()) return;
    gl.UseProgram(surface_program);
    gl.Uniform3f(gl.GetUniformLocation(surface_program, "color"), r, g, b);
    gl.Uniform1i(gl.GetUniformLocation(surface_program, "lit"), lit ? 1 : 0);
    gl.BindVertexArray(surface_vao);
    gl.BindBuffer(GL_ARRAY_BUFFER, surface_vbo);
    gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(SurfaceVertex)),
                  vertices.data(), GL_STREAM_DRAW);
    gl.DrawArrays(mode, 0, static_cast<GLsizei>(vertices.size()));
  }
};

Renderer::Renderer(int threads) : impl_(std::make_unique<Impl>()) {
  LoadGl();
  if (threads > 0 && std::getenv("LP_NUM_THREADS") == nullptr) {
    setenv("LP_NUM_THREADS", std::to_string(threads).c_str(), 0);
  }
  const int attributes[] = {OSMESA_FORMAT,
                            OSMESA_RGBA,
                            OSMESA_DEPTH_BITS,
                            24,
                            OSMESA_STENCIL_BITS,
                            0,
                            OSMESA_ACCUM_BITS,
                            0,
                            OSMESA_PROFILE,
                            OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION,
                            3,
                            OSMESA_CONTEXT_MINOR_VERSION,
                            3,
                            0};
  impl_->context = osmesa.CreateContextAttribs(attributes, nullptr);
  if (impl_->context == nullptr) {
    throw std::runtime_error("render: OSMesa could not create a GL 3.3 core context");
  }
  impl_->Bind(64, 64);  // a context needs a buffer before any GL call

  Impl& m = *impl_;
  m.sphere_program = Link(kSphereVertex, kSphereFragment);
  m.surface_program = Link(kSurfaceVertex, kSurfaceFragment);

  // One vertex array and buffer per primitive: attribute 0 is a float vector of `size0`, attribute
  // 1 a vector of `size1` (`type1`, normalised when integer) at byte `offset1` of each vertex.
  auto vertex_array = [](GLuint* vao, GLuint* vbo, GLsizei stride, GLint size0, GLint size1,
                         GLenum type1, size_t offset1) {
    gl.GenVertexArrays(1, vao);
    gl.GenBuffers(1, vbo);
    gl.BindVertexArray(*vao);
    gl.BindBuffer(GL_ARRAY_BUFFER, *vbo);
    gl.EnableVertexAttribArray(0);
    gl.VertexAttribPointer(0, size0, GL_FLOAT, GL_FALSE, stride, nullptr);
    gl.EnableVertexAttribArray(1);
    gl.VertexAttribPointer(1, size1, type1, type1 == GL_FLOAT ? GL_FALSE : GL_TRUE, stride,
                           reinterpret_cast<const void*>(offset1));
  };
  vertex_array(&m.sphere_vao, &m.sphere_vbo, sizeof(SphereVertex), 4, 4, GL_UNSIGNED_BYTE,
               offsetof(SphereVertex, rgba));
  vertex_array(&m.surface_vao, &m.surface_vbo, sizeof(SurfaceVertex), 3, 3, GL_FLOAT,
               offsetof(SurfaceVertex, nx));
  gl.BindVertexArray(0);
}

Renderer::~Renderer() {
  if (impl_->context != nullptr) osmesa.DestroyContext(impl_->context);
}

size_t Renderer::drawn_particles() const { return impl_->drawn; }
const Image& Renderer::image() const { return impl_->image; }

std::string Renderer::Description() const {
  const auto* renderer = reinterpret_cast<const char*>(gl.GetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(gl.GetString(GL_VERSION));
  return std::string(renderer ? renderer : "?") + " (" + (version ? version : "?") + ")";
}

const Image& Renderer::Render(const sim::WorldView& view, const RenderSettings& settings) {
  Impl& m = *impl_;
  const Camera& camera = settings.camera;
  if (camera.width < 1 || camera.height < 1) {
    throw std::invalid_argument("render: image size must be positive");
  }
  m.Bind(camera.width, camera.height);

  // Camera and light.
  const Mat4 view_matrix = ViewMatrix(camera);
  const Mat4 proj_matrix = ProjectionMatrix(camera);
  const std::array<float, 16> view_f = ToFloat(view_matrix);
  const std::array<float, 16> proj_f = ToFloat(proj_matrix);
  const float tan_y = static_cast<float>(std::tan(0.5 * camera.fov_y_deg * kPi / 180.0));
  const float tan_x = tan_y * static_cast<float>(camera.width) / static_cast<float>(camera.height);
  const float light_norm =
      std::sqrt(kLightDirection[0] * kLightDirection[0] + kLightDirection[1] * kLightDirection[1] +
                kLightDirection[2] * kLightDirection[2]);
  const float light[3] = {kLightDirection[0] / light_norm, kLightDirection[1] / light_norm,
                          kLightDirection[2] / light_norm};
  for (GLuint program : {m.sphere_program, m.surface_program}) {
    gl.UseProgram(program);
    gl.UniformMatrix4fv(gl.GetUniformLocation(program, "view"), 1, GL_FALSE, view_f.data());
    gl.UniformMatrix4fv(gl.GetUniformLocation(program, "proj"), 1, GL_FALSE, proj_f.data());
    gl.Uniform3fv(gl.GetUniformLocation(program, "light"), 1, light);
    gl.Uniform1f(gl.GetUniformLocation(program, "ambient"), kAmbient);
  }

  gl.Viewport(0, 0, camera.width, camera.height);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);
  gl.Enable(GL_PROGRAM_POINT_SIZE);
  gl.ClearColor(settings.background.r / 255.0f, settings.background.g / 255.0f,
                settings.background.b / 255.0f, 1.0f);
  gl.ClearDepth(1.0);
  gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);

  // Scenery: the ground around the bed box and the box's twelve edges.
  const dem::Vec3 lo = view.box_min, hi = view.box_max;
  const bool has_box = hi.x > lo.x && hi.y > lo.y && hi.z > lo.z;
  if (settings.scenery && has_box) {
    const dem::Vec3 e = hi - lo;
    const double mx = 0.6 * e.x, my = 0.6 * e.y;
    // The ground lies a hair below the floor so floor-resting spheres are not cut by it.
    const double z = lo.z - 1e-4 * std::max(e.x, e.y);
    const dem::Vec3 a{lo.x - mx, lo.y - my, z}, b{hi.x + mx, lo.y - my, z},
        c{hi.x + mx, hi.y + my, z}, d{lo.x - mx, hi.y + my, z};
    m.triangles.clear();
    AddTriangle(&m.triangles, a, b, c);
    AddTriangle(&m.triangles, a, c, d);
    m.DrawSurfaces(m.triangles, GL_TRIANGLES, 0.66f, 0.62f, 0.55f, settings.shading);
    m.lines.clear();
    for (int k = 0; k < 8; ++k) {
      for (int axis = 0; axis < 3; ++axis) {
        if (k & (1 << axis)) continue;  // each edge once, from its low end
        const int j = k | (1 << axis);
        for (int corner : {k, j}) {
          m.lines.push_back({static_cast<float>((corner & 1) ? hi.x : lo.x),
                             static_cast<float>((corner & 2) ? hi.y : lo.y),
                             static_cast<float>((corner & 4) ? hi.z : lo.z), 0, 0, 1});
        }
      }
    }
    m.DrawSurfaces(m.lines, GL_LINES, 0.25f, 0.26f, 0.30f, false);
  }

  // Meshes: body-frame triangles moved to the world on the CPU, flat normals; the scoop and
  // obstacles in one colour, the arm's links in another.
  for (const bool arm_links : {false, true}) {
    m.triangles.clear();
    for (const sim::MeshView& mesh_view : view.meshes) {
      if (mesh_view.mesh == nullptr || (mesh_view.role == sim::MeshRole::kArmLink) != arm_links)
        continue;
      const dem::TriangleMesh& mesh = *mesh_view.mesh;
      for (const auto& t : mesh.triangles) {
        AddTriangle(&m.triangles, dem::Apply(mesh_view.pose, mesh.vertices[t[0]]),
                    dem::Apply(mesh_view.pose, mesh.vertices[t[1]]),
                    dem::Apply(mesh_view.pose, mesh.vertices[t[2]]));
      }
    }
    if (arm_links) {
      m.DrawSurfaces(m.triangles, GL_TRIANGLES, 0.90f, 0.55f, 0.20f, settings.shading);
    } else {
      m.DrawSurfaces(m.triangles, GL_TRIANGLES, 0.74f, 0.76f, 0.80f, settings.shading);
    }
  }

  // Particles: culled (see Render's header comment), coloured on the CPU (one field value and
  // one colour-map lookup each), drawn as points.
  const size_t n = view.particles != nullptr ? view.particles->size() : 0;
  m.drawn = 0;
  if (n > 0) {
    const dem::Particles& p = *view.particles;
    const double pixel_scale = 0.5 * camera.height * proj_matrix[5];
    m.visible.clear();
    if (settings.cull_hidden) {
      const int w = camera.width, h = camera.height;
      m.cells.assign(static_cast<size_t>(w) * h, std::numeric_limits<float>::infinity());
      m.footprints.resize(n);
      double near_plane = 0, far_plane = 0;
      ClipPlanes(camera, &near_plane, &far_plane);
      const Mat4& v = view_matrix;
      const double sx = 0.5 * camera.width * proj_matrix[0], sy = pixel_scale;
      // Pass 1: every pixel centre within f r / |c| of a sphere's projected centre sees that
      // sphere (the pinhole map stretches angles by at least f, so the pixel's ray is within
      // r / |c| rad of the centre's and hits the sphere), at a depth no farther than centre + r.
      for (size_t i = 0; i < n; ++i) {
        const dem::Vec3& x = p.x[i];
        const double cx = v[0] * x.x + v[4] * x.y + v[8] * x.z + v[12];
        const double cy = v[1] * x.x + v[5] * x.y + v[9] * x.z + v[13];
        const double z = -(v[2] * x.x + v[6] * x.y + v[10] * x.z + v[14]);
        Impl::Footprint& f = m.footprints[i];
        const double r = p.radius[i];
        if (!(z > near_plane && z < far_plane && z > r)) {
          f.depth = -1;  // GL clips a point whose centre is outside the view volume
          continue;
        }
        f.px = static_cast<float>(0.5 * camera.width + sx * cx / z);
        f.py = static_cast<float>(0.5 * camera.height + sy * cy / z);
        f.depth = static_cast<float>(z);
        const double dist = std::sqrt(cx * cx + cy * cy + z * z);
        // The radius of a disk surely holding the silhouette: its semi-major axis, which the
        // vertex shader also sizes the sprite by, plus a pixel for the ellipse's offset from the
        // projected centre (a fraction of a pixel) and rounding; the radius of the disk surely
        // inside the silhouette, less a margin for rounding.
        f.half = static_cast<float>(pixel_scale * r / std::sqrt(z * z - r * r) * dist / z + 1.0);
        f.inner = static_cast<float>(0.98 * pixel_scale * r / dist - 0.02);
        if (f.inner <= 0) continue;
        const float back = static_cast<float>(z + r);
        const float r2 = f.inner * f.inner;
        const int x0 = std::max(static_cast<int>(std::ceil(f.px - f.inner - 0.5f)), 0);
        const int x1 = std::min(static_cast<int>(std::floor(f.px + f.inner - 0.5f)), w - 1);
        const int y0 = std::max(static_cast<int>(std::ceil(f.py - f.inner - 0.5f)), 0);
        const int y1 = std::min(static_cast<int>(std::floor(f.py + f.inner - 0.5f)), h - 1);
        for (int yy = y0; yy <= y1; ++yy) {
          const float dy = yy + 0.5f - f.py;
          float* row = m.cells.data() + static_cast<size_t>(yy) * w;
          for (int xx = x0; xx <= x1; ++xx) {
            const float dx = xx + 0.5f - f.px;
            if (dx * dx + dy * dy < r2) row[xx] = std::min(row[xx], back);
          }
        }
      }
      // Blocks of kBlock x kBlock pixels keep their farthest value, so pass 2 skips a block
      // that is nearer than a sphere's front everywhere without reading its pixels.
      constexpr int kBlock = 4;
      const int bw = (w + kBlock - 1) / kBlock, bh = (h + kBlock - 1) / kBlock;
      m.blocks.assign(static_cast<size_t>(bw) * bh, 0.0f);
      for (int yy = 0; yy < h; ++yy) {
        const float* row = m.cells.data() + static_cast<size_t>(yy) * w;
        float* block_row = m.blocks.data() + static_cast<size_t>(yy / kBlock) * bw;
        for (int xx = 0; xx < w; ++xx) {
          block_row[xx / kBlock] = std::max(block_row[xx / kBlock], row[xx]);
        }
      }
      // Pass 2: a sphere is hidden when at every pixel centre its silhouette could cover,
      // something lies nearer than its front (centre depth - r).
      for (size_t i = 0; i < n; ++i) {
        const Impl::Footprint& f = m.footprints[i];
        if (f.depth < 0) continue;
        const float front = f.depth - static_cast<float>(p.radius[i]);
        const float r2 = f.half * f.half;
        const int x0 = std::max(static_cast<int>(std::floor(f.px - f.half)), 0);
        const int x1 = std::min(static_cast<int>(std::floor(f.px + f.half)), w - 1);
        const int y0 = std::max(static_cast<int>(std::floor(f.py - f.half)), 0);
        const int y1 = std::min(static_cast<int>(std::floor(f.py + f.half)), h - 1);
        bool hidden = true;
        for (int by = y0 / kBlock; by <= y1 / kBlock && hidden; ++by) {
          for (int bx = x0 / kBlock; bx <= x1 / kBlock && hidden; ++bx) {
            if (m.blocks[static_cast<size_t>(by) * bw + bx] < front) continue;
            const int ya = std::max(y0, by * kBlock), yb = std::min(y1, by * kBlock + kBlock - 1);
            const int xa = std::max(x0, bx * kBlock), xb = std::min(x1, bx * kBlock + kBlock - 1);
            for (int yy = ya; yy <= yb && hidden; ++yy) {
              const float dy = yy + 0.5f - f.py;
              const float* row = m.cells.data() + static_cast<size_t>(yy) * w;
              for (int xx = xa; xx <= xb; ++xx) {
                const float dx = xx + 0.5f - f.px;
                if (dx * dx + dy * dy <= r2 && !(row[xx] < front)) {
                  hidden = false;
                  break;
                }
              }
            }
          }
        }
        if (!hidden) m.visible.push_back(static_cast<uint32_t>(i));
      }
    } else {
      m.visible.resize(n);
      for (size_t i = 0; i < n; ++i) m.visible[i] = static_cast<uint32_t>(i);
    }

    ComputeField(view, settings.color_by, &m.field);
    const size_t drawn = m.visible.size();
    m.spheres.resize(drawn);
    const double span = settings.range_max - settings.range_min;
    const double scale = span > 0 ? 1.0 / span : 0.0;
    for (size_t k = 0; k < drawn; ++k) {
      const size_t i = m.visible[k];
      const Rgb c = settings.color_by == ColorField::kMaterial
                        ? MaterialColor(p.material[i])
                        : Viridis((m.field[i] - settings.range_min) * scale);
      m.spheres[k] = {static_cast<float>(p.x[i].x),
                      static_cast<float>(p.x[i].y),
                      static_cast<float>(p.x[i].z),
                      static_cast<float>(p.radius[i]),
                      {To8(c.r), To8(c.g), To8(c.b), 255}};
    }
    m.drawn = drawn;
    gl.UseProgram(m.sphere_program);
    gl.Uniform1f(gl.GetUniformLocation(m.sphere_program, "pixel_scale"),
                 static_cast<float>(pixel_scale));
    gl.Uniform2f(gl.GetUniformLocation(m.sphere_program, "viewport"),
                 static_cast<float>(camera.width), static_cast<float>(camera.height));
    gl.Uniform2f(gl.GetUniformLocation(m.sphere_program, "tan_half"), tan_x, tan_y);
    gl.Uniform1i(gl.GetUniformLocation(m.sphere_program, "shading"), settings.shading ? 1 : 0);
    gl.BindVertexArray(m.sphere_vao);
    gl.BindBuffer(GL_ARRAY_BUFFER, m.sphere_vbo);
    // The buffer grows only: re-allocating it every frame costs page faults.
    const size_t bytes = drawn * sizeof(SphereVertex);
    if (bytes > m.sphere_capacity) {
      m.sphere_capacity = bytes + bytes / 4;
      gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(m.sphere_capacity), nullptr,
                    GL_STREAM_DRAW);
    }
    if (drawn > 0) {
      gl.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(bytes), m.spheres.data());
      gl.DrawArrays(GL_POINTS, 0, static_cast<GLsizei>(drawn));
    }
  }
  gl.BindVertexArray(0);
  gl.Finish();  // the image is in m.image once GL is done
  const GLenum error = gl.GetError();
  if (error != GL_NO_ERROR) {
    throw std::runtime_error("render: GL error " + std::to_string(error));
  }

  // Overlays, drawn into the image on the CPU.
  if (settings.overlays) {
    const Rgba8 ink{25, 27, 32, 255};
    const int s = camera.height >= 480 ? 2 : 1;  // font scale
    // The caption and the fault line on a light plate: readable over the orange links.
    const std::string caption = Caption(view);
    const std::string fault = view.faults.empty() ? "" : "FAULT " + view.faults;
    const int lines = fault.empty() ? 1 : 2;
    m.image.BlendRect(8 * s, 7 * s, std::max(TextWidth(caption, s), TextWidth(fault, s)) + 8 * s,
                      lines * kGlyphHeight * s + 4 * s, kPlate);
    DrawText(&m.image, 12 * s, 10 * s, caption, s, ink);
    if (!fault.empty())
      DrawText(&m.image, 12 * s, 10 * s + kGlyphHeight * s, fault, s, kMarginOver);
    DrawTorqueBars(&m.image, view.joints, s, ink);
    if (n > 0) {
      // Colour bar at the right edge: the title above, the range's ends beside it.
      const int bar_w = 12 * s, bar_h = camera.height * 2 / 5;
      const int bar_x = camera.width - bar_w - 12 * s, bar_y = 16 * s + kGlyphHeight * s;
      std::string title = FieldName(settings.color_by);
      if (*FieldUnit(settings.color_by) != '\0')
        title += std::string(" [") + FieldUnit(settings.color_by) + "]";
      DrawText(&m.image, camera.width - 12 * s - TextWidth(title, s), 10 * s, title, s, ink);
      if (settings.color_by == ColorField::kMaterial) {
        const int lo_m = static_cast<int>(std::floor(settings.range_min));
        const int hi_m = std::max(lo_m, static_cast<int>(std::ceil(settings.range_max)));
        int y = bar_y;
        for (int k = lo_m; k <= hi_m && k - lo_m < 16; ++k, y += bar_w + 4 * s) {
          const Rgb c = MaterialColor(k);
          m.image.FillRect(bar_x, y, bar_w, bar_w, {To8(c.r), To8(c.g), To8(c.b), 255});
          const std::string label = std::to_string(k);
          DrawText(&m.image, bar_x - 4 * s - TextWidth(label, s), y + (bar_w - 9 * s) / 2, label, s,
                   ink);
        }
      } else {
        for (int y = 0; y < bar_h; ++y) {
          const Rgb c = Viridis(1.0 - static_cast<double>(y) / std::max(bar_h - 1, 1));
          m.image.FillRect(bar_x, bar_y + y, bar_w, 1, {To8(c.r), To8(c.g), To8(c.b), 255});
        }
        const std::string top = Format("%.3g", settings.range_max);
        const std::string bottom = Format("%.3g", settings.range_min);
        DrawText(&m.image, bar_x - 4 * s - TextWidth(top, s), bar_y, top, s, ink);
        DrawText(&m.image, bar_x - 4 * s - TextWidth(bottom, s), bar_y + bar_h - 9 * s, bottom, s,
                 ink);
      }
    }
  }
  return m.image;
}

std::string Caption(const sim::WorldView& view) {
  std::string text = "t = " + Format("%.5f", view.time) + " s";
  if (view.pass > 0) {
    text += "   pass " + std::to_string(view.pass) + "   rho = " + Format("%.4f", view.rho) + " m";
  }
  if (view.pass > 0 || view.force > 0) text += "   |F| = " + Format("%.3g", view.force) + " N";
  return text;
}

}  // namespace render

namespace render {

double TorqueMargin(const sim::JointView& joint) {
  return joint.limit > 0 ? 1.0 - std::abs(joint.torque) / joint.limit : 0.0;
}

double TorqueBarFraction(const sim::JointView& joint) {
  return 1.0 - std::max(TorqueMargin(joint), 0.0);
}

Rgba8 MarginColor(double margin) {
  if (margin > kMarginLow) return kMarginOk;
  if (margin > 0) return kMarginWarn;
  return kMarginOver;
}

void DrawTorqueBars(Image* image, const std::vector<sim::JointView>& joints, int s, Rgba8 ink) {
  if (joints.empty()) return;
  // A row per joint, from the bottom-left corner up: name, then the track and its filled part.
  int label_w = 0;
  for (const sim::JointView& j : joints) label_w = std::max(label_w, TextWidth(j.name, s));
  const int track_w = 100 * s, bar_h = 7 * s, row_h = kGlyphHeight * s + 2 * s;
  const int x = 12 * s, bar_x = x + label_w + 6 * s;
  int y = image->height() - 10 * s - static_cast<int>(joints.size()) * row_h;
  const std::string title = "|torque| / effort limit";
  image->BlendRect(x - 4 * s, y - row_h - 3 * s,
                   std::max(TextWidth(title, s), bar_x - x + track_w + s) + 8 * s,
                   static_cast<int>(joints.size() + 1) * row_h + 4 * s, kPlate);
  DrawText(image, x, y - row_h, title, s, ink);
  for (const sim::JointView& j : joints) {
    DrawText(image, x, y, j.name, s, ink);
    const int bar_y = y + (kGlyphHeight * s - bar_h) / 2 - s;
    image->FillRect(bar_x - s, bar_y - s, track_w + 2 * s, bar_h + 2 * s, ink);
    image->FillRect(bar_x, bar_y, track_w, bar_h, {255, 255, 255, 255});
    const int filled = static_cast<int>(std::lround(TorqueBarFraction(j) * track_w));
    image->FillRect(bar_x, bar_y, filled, bar_h, MarginColor(TorqueMargin(j)));
    y += row_h;
  }
}

}  // namespace render
