// The renderer against closed forms: where a pinhole camera puts a sphere and how large, which
// colour the colour map gives, what an empty scene shows, that impostor depth cuts a sphere
// against a mesh where the geometry says, that occlusion culling leaves the image unchanged, the
// arm's torque bars by their margin rule, that an arm link is drawn, and the caption's clock.
// Every expectation is computed here from the camera parameters, not from render/camera.cpp.
#include "render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <utility>

#include "render/bench.h"
#include "render/camera.h"
#include "render/frames.h"
#include "sim/files/arm_geometry.h"
#include "sim/input/scene.h"

namespace render {
namespace {

constexpr double kPi = 3.14159265358979323846;

// One renderer (one OSMesa context) for the whole suite: creating it compiles the shaders.
Renderer& SharedRenderer() {
  static Renderer renderer(1);
  return renderer;
}

dem::Vec3 Unit(const dem::Vec3& v) { return (1.0 / dem::Norm(v)) * v; }

// Pinhole projection written out: the camera looks along f = unit(target - eye), with right
// r = unit(f x up) and true up u = r x f; focal length in pixels F = (H / 2) / tan(fov_y / 2).
// A point at offset d = x - eye projects to column W/2 + F (d.r)/(d.f) and row (from the top)
// H/2 - F (d.u)/(d.f).
struct Pinhole {
  dem::Vec3 eye, r, u, f;
  double focal_px, cx, cy;
  explicit Pinhole(const Camera& c) {
    eye = c.position;
    f = Unit(c.target - c.position);
    r = Unit(dem::Cross(f, c.up));
    u = dem::Cross(r, f);
    focal_px = 0.5 * c.height / std::tan(0.5 * c.fov_y_deg * kPi / 180);
    cx = 0.5 * c.width;
    cy = 0.5 * c.height;
  }
  void Project(const dem::Vec3& x, double* col, double* row) const {
    const dem::Vec3 d = x - eye;
    *col = cx + focal_px * dem::Dot(d, r) / dem::Dot(d, f);
    *row = cy - focal_px * dem::Dot(d, u) / dem::Dot(d, f);
  }
  // Equivalent radius sqrt(a b) of the ellipse a sphere of radius `radius` at x projects to: the
  // cone of half-angle alpha (sin alpha = radius / |d|) around a ray theta off the axis cuts the
  // image plane in an ellipse with b = F sin(alpha) / sqrt(cos^2 theta - sin^2 alpha) and
  // a = F sin(alpha) cos(alpha) / (cos^2 theta - sin^2 alpha).
  double Radius(const dem::Vec3& x, double radius) const {
    const dem::Vec3 d = x - eye;
    const double s = radius / dem::Norm(d), c = std::sqrt(1 - s * s);
    const double cos_t = dem::Dot(d, f) / dem::Norm(d);
    const double k = cos_t * cos_t - s * s;
    const double b = focal_px * s / std::sqrt(k), a = focal_px * s * c / k;
    return std::sqrt(a * b);
  }
};

RenderSettings PlainSettings() {
  RenderSettings s;
  s.camera.position = {0.3, -0.4, 0.25};
  s.camera.target = {0.02, 0.01, 0.03};
  s.camera.fov_y_deg = 40;
  s.camera.width = 640;
  s.camera.height = 480;
  s.overlays = false;
  s.scenery = false;
  return s;
}

// Particles with the fields the renderer reads.
void AddSphere(dem::Particles* p, const dem::Vec3& x, double radius, const dem::Vec3& v = {},
               int material = 0) {
  p->id.push_back(static_cast<int64_t>(p->id.size()));
  p->x.push_back(x);
  p->v.push_back(v);
  p->radius.push_back(radius);
  p->material.push_back(material);
}

// Non-background pixels of `image`: count and centroid (column, row from the top).
int Footprint(const Image& image, Rgba8 background, double* col, double* row) {
  int count = 0;
  double sc = 0, sr = 0;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      if (image.At(x, y) != background) {
        ++count;
        sc += x + 0.5;
        sr += y + 0.5;
      }
    }
  }
  if (count > 0) {
    *col = sc / count;
    *row = sr / count;
  }
  return count;
}

// (a) One sphere, off the optical axis: the centroid of its pixels lies within 2 px of the
// pinhole projection of its centre, and sqrt(area / pi) within 10% of the projected ellipse's
// equivalent radius (Pinhole::Radius). The ellipse's centre is offset from the projected centre
// by F sin(theta) cos(theta) sin^2(alpha) / (cos^2 theta - sin^2 alpha) < 0.1 px here.
TEST(RendererTest, OneSphereAtThePinholeProjection) {
  const RenderSettings settings = PlainSettings();
  const Pinhole pinhole(settings.camera);
  for (const dem::Vec3& x :
       {dem::Vec3{0.02, 0.01, 0.03}, dem::Vec3{0.09, 0.03, 0.07}, dem::Vec3{-0.05, -0.02, 0.0}}) {
    dem::Particles p;
    AddSphere(&p, x, 0.01);
    sim::WorldView view;
    view.particles = &p;
    const Image& image = SharedRenderer().Render(view, settings);
    double col = 0, row = 0, expected_col = 0, expected_row = 0;
    const int area = Footprint(image, settings.background, &col, &row);
    pinhole.Project(x, &expected_col, &expected_row);
    EXPECT_NEAR(col, expected_col, 2.0) << "sphere at " << x.x << ", " << x.y << ", " << x.z;
    EXPECT_NEAR(row, expected_row, 2.0);
    const double expected_radius = pinhole.Radius(x, 0.01);
    EXPECT_GT(expected_radius, 8.0);  // large enough for a 10% check to mean something
    EXPECT_NEAR(std::sqrt(area / kPi), expected_radius, 0.1 * expected_radius);
  }
}

// (b) Colour map. Three spheres with speeds 0, 0.5 and 1 in a range [0, 1], without shading: the
// pixel at each projected centre is round(255 * viridis(t)) with matplotlib's published viridis
// values, within 1 (8-bit rounding). With shading, the on-axis sphere's centre pixel has the
// normal facing the camera, n = (0, 0, 1) in view space, so it shows
// c * (kAmbient + (1 - kAmbient) * L_z / |L|), within 2 (the pixel centre is off the exact centre
// by < 0.5 px, the normal by < 0.5 / 20 rad).
// The three spheres at xs are drawn flat in viridis at 0, 0.5 and 1 (8-bit, to 1).
void ExpectViridisEnds(const Image& image, const Pinhole& pinhole, const dem::Vec3 xs[3]) {
  const int expected[3][3] = {{68, 1, 84}, {33, 145, 140}, {253, 231, 37}};  // viridis 0, .5, 1
  for (int k = 0; k < 3; ++k) {
    double col = 0, row = 0;
    pinhole.Project(xs[k], &col, &row);
    const Rgba8 c = image.At(static_cast<int>(col), static_cast<int>(row));
    EXPECT_NEAR(c.r, expected[k][0], 1) << "sphere " << k;
    EXPECT_NEAR(c.g, expected[k][1], 1) << "sphere " << k;
    EXPECT_NEAR(c.b, expected[k][2], 1) << "sphere " << k;
  }
}

TEST(RendererTest, ColoursFollowTheColourMap) {
  RenderSettings settings = PlainSettings();
  settings.range_min = 0;
  settings.range_max = 1;
  settings.shading = false;
  const Pinhole pinhole(settings.camera);
  // Spheres side by side along the camera's right vector, the middle one on the axis.
  const dem::Vec3 centre = settings.camera.target;
  const dem::Vec3 xs[3] = {centre - 0.06 * pinhole.r, centre, centre + 0.06 * pinhole.r};
  const double speeds[3] = {0, 0.5, 1};
  dem::Particles p;
  for (int k = 0; k < 3; ++k) AddSphere(&p, xs[k], 0.02, {speeds[k], 0, 0});
  sim::WorldView view;
  view.particles = &p;
  ExpectViridisEnds(SharedRenderer().Render(view, settings), pinhole, xs);

  settings.shading = true;
  const Image& lit = SharedRenderer().Render(view, settings);
  const double lz = kLightDirection[2] / std::sqrt(kLightDirection[0] * kLightDirection[0] +
                                                   kLightDirection[1] * kLightDirection[1] +
                                                   kLightDirection[2] * kLightDirection[2]);
  const double k = kAmbient + (1 - kAmbient) * lz;
  double col = 0, row = 0;
  pinhole.Project(xs[1], &col, &row);
  const Rgba8 c = lit.At(static_cast<int>(col), static_cast<int>(row));
  EXPECT_NEAR(c.r, 255 * 0.127568 * k, 2);
  EXPECT_NEAR(c.g, 255 * 0.566949 * k, 2);
  EXPECT_NEAR(c.b, 255 * 0.550556 * k, 2);
}

// The broken_bonds field (issue 44): each particle's count from view.broken_bonds, 0 without;
// counts 0, 3, 6 over the range [0, 6] draw viridis at 0, 0.5 and 1 (as the speed field above).
TEST(RendererTest, ColoursByBrokenBonds) {
  ColorField field = ColorField::kSpeed;
  ASSERT_TRUE(ParseColorField("broken_bonds", &field));
  EXPECT_EQ(field, ColorField::kBrokenBonds);
  EXPECT_STREQ(FieldName(field), "broken_bonds");
  RenderSettings settings = PlainSettings();
  settings.color_by = ColorField::kBrokenBonds;
  settings.range_min = 0;
  settings.range_max = 6;
  settings.shading = false;
  const Pinhole pinhole(settings.camera);
  const dem::Vec3 centre = settings.camera.target;
  const dem::Vec3 xs[3] = {centre - 0.06 * pinhole.r, centre, centre + 0.06 * pinhole.r};
  dem::Particles p;
  for (int k = 0; k < 3; ++k) AddSphere(&p, xs[k], 0.02, {0, 0, 0});
  sim::WorldView view;
  view.particles = &p;
  std::vector<float> values;
  ComputeField(view, field, &values);  // no counts: 0 each
  EXPECT_EQ(values, std::vector<float>(3, 0.0f));
  view.broken_bonds = {0, 3, 6};
  ComputeField(view, field, &values);
  EXPECT_EQ(values, view.broken_bonds);
  ExpectViridisEnds(SharedRenderer().Render(view, settings), pinhole, xs);
  // A saved run's range: [0, the most seen], at least [0, 1].
  AutoRange range;
  range.Update(field, {0, 0, 0});
  EXPECT_EQ(range.max(), 1.0);
  range.Update(field, {0, 4, 1});
  EXPECT_EQ(range.max(), 4.0);
}

// (c) A view with nothing in it is the background colour at every pixel.
TEST(RendererTest, EmptySceneIsBackground) {
  RenderSettings settings = PlainSettings();
  settings.scenery = true;  // no box in the view: nothing to draw
  dem::Particles none;
  sim::WorldView view;
  view.particles = &none;
  const Image& image = SharedRenderer().Render(view, settings);
  double col = 0, row = 0;
  EXPECT_EQ(Footprint(image, settings.background, &col, &row), 0);
}

// Impostor depth against a mesh. Camera on the +z axis looking down at a box mesh whose top face
// is the plane z = 0, moved there by a pose (rotation about z by 90 degrees and a translation);
// a sphere of radius R centred h = R/2 below that plane pokes out as a cap whose outline is the
// circle of radius sqrt(R^2 - h^2) = 0.866 R. Seen from 1 m (R << 1 m, near-orthographic), the
// visible sphere pixels make a disk of radius 0.866 F R / 1 m (within 5%); a sprite with
// flat depth would show all or nothing. The mesh itself covers the pixel at the box's projected
// top-face corner region (not background, not sphere-coloured).
TEST(RendererTest, SphereDepthCutsAgainstAMesh) {
  RenderSettings settings = PlainSettings();
  settings.camera.position = {0, 0, 1};
  settings.camera.target = {0, 0, 0};
  settings.camera.up = {0, 1, 0};
  settings.shading = false;
  settings.range_max = 1;
  const dem::TriangleMesh box = BoxMesh({-0.05, -0.05, -0.1}, {0.05, 0.05, 0});
  const double radius = 0.02, h = 0.01;
  dem::Particles p;
  AddSphere(&p, {0, 0, -h}, radius, {1, 0, 0});  // speed 1: viridis(1), yellow
  sim::WorldView view;
  view.particles = &p;
  sim::MeshView mesh_view;
  mesh_view.mesh = &box;
  mesh_view.pose.orientation = dem::AxisAngle({0, 0, 1}, kPi / 2);
  mesh_view.pose.position = {0.0, 0.0, 0.0};
  view.meshes.push_back(mesh_view);
  const Image& image = SharedRenderer().Render(view, settings);
  const Rgba8 yellow{253, 231, 37, 255};
  int cap = 0;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const Rgba8 c = image.At(x, y);
      cap += std::abs(c.r - yellow.r) <= 1 && std::abs(c.g - yellow.g) <= 1 &&
             std::abs(c.b - yellow.b) <= 1;
    }
  }
  const double focal = 0.5 * settings.camera.height / std::tan(0.5 * 40 * kPi / 180);
  const double expected = std::sqrt(radius * radius - h * h) * focal / 1.0;
  EXPECT_NEAR(std::sqrt(cap / kPi), expected, 0.05 * expected);
  // The box's top face (mesh colour, unlit) around the sphere, 0.04 m off the axis.
  const Rgba8 face = image.At(static_cast<int>(320 + 0.04 * focal), 240);
  EXPECT_NE(face, settings.background);
  EXPECT_NE(face, yellow);
}

// A deep pile of spheres seen obliquely: culling hidden particles hands GL far fewer of them and
// gives the very same image, pixel for pixel.
TEST(RendererTest, OcclusionCullingKeepsTheImage) {
  RenderSettings settings = PlainSettings();
  settings.scenery = true;
  settings.overlays = true;
  settings.range_max = 0.02;
  dem::Particles p;
  for (int k = 0; k < 8; ++k) {
    for (int j = 0; j < 30; ++j) {
      for (int i = 0; i < 30; ++i) {
        AddSphere(&p, {0.004 * i + 0.002 * (k % 2), 0.004 * j, 0.002 + 0.0036 * k}, 0.00195,
                  {0.001 * ((i * 7 + j * 3 + k) % 20), 0, 0});
      }
    }
  }
  sim::WorldView view;
  view.particles = &p;
  view.box_min = {-0.002, -0.002, 0};
  view.box_max = {0.12, 0.12, 0.05};
  ApplyCameraPreset("trench_oblique", view.box_min, view.box_max, &settings.camera);
  settings.cull_hidden = true;
  const Image culled = SharedRenderer().Render(view, settings);
  const size_t drawn = SharedRenderer().drawn_particles();
  settings.cull_hidden = false;
  const Image& full = SharedRenderer().Render(view, settings);
  EXPECT_EQ(SharedRenderer().drawn_particles(), p.size());
  EXPECT_LT(drawn, p.size() / 2);
  int differing = 0;
  for (int y = 0; y < full.height(); ++y) {
    for (int x = 0; x < full.width(); ++x) differing += full.At(x, y) != culled.At(x, y);
  }
  EXPECT_EQ(differing, 0);
}

// The torque bar of a joint, by the rule in renderer.h: margin m = 1 - |tau| / limit, filled
// length min(|tau| / limit, 1) of the track, green for m > 0.25, amber for 0 < m <= 0.25, red for
// m <= 0. Closed form at six torques; then drawn: the pixels of each bar's colour are its filled
// length (round(fraction x 100 s) px) times its height (7 s px), s = 2 the font scale, and a bar of
// torque 0 draws no colour at all.
TEST(RendererTest, TorqueBarsFollowTheMarginRule) {
  const double limit = 73;
  struct Case {
    double torque, margin, fraction;
    Rgba8 color;
  };
  const Case cases[] = {{0, 1, 0, kMarginOk},
                        {-36.5, 0.5, 0.5, kMarginOk},
                        {0.8 * limit, 0.2, 0.8, kMarginWarn},
                        {-limit, 0, 1, kMarginOver},
                        {1.3 * limit, -0.3, 1, kMarginOver},
                        {0.75 * limit, 0.25, 0.75, kMarginWarn}};
  for (const Case& c : cases) {
    const sim::JointView joint{"j", c.torque, limit};
    EXPECT_NEAR(TorqueMargin(joint), c.margin, 1e-12) << c.torque;
    EXPECT_NEAR(TorqueBarFraction(joint), c.fraction, 1e-12) << c.torque;
    EXPECT_EQ(MarginColor(TorqueMargin(joint)), c.color) << c.torque;
  }
  Image image;
  image.Resize(640, 360);
  image.FillRect(0, 0, 640, 360, {255, 255, 255, 255});
  const int s = 2;
  DrawTorqueBars(&image,
                 {{"j_a", 0.5 * limit, limit},
                  {"j_b", -0.9 * limit, limit},
                  {"j_c", 2 * limit, limit},
                  {"j_d", 0, limit}},
                 s, {0, 0, 0, 255});
  int ok = 0, warn = 0, over = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      ok += image.At(x, y) == kMarginOk;
      warn += image.At(x, y) == kMarginWarn;
      over += image.At(x, y) == kMarginOver;
    }
  EXPECT_EQ(ok, 50 * s * 7 * s);
  EXPECT_EQ(warn, 90 * s * 7 * s);
  EXPECT_EQ(over, 100 * s * 7 * s);
}

// An arm link is drawn: the lander arm's links (sim::ArmGeometry from assets/lander_arm.urdf) at
// the digging pose, the camera 0.5 m from the centre of l_dist's box looking at it. Unlit, the
// image centre shows the arm's colour (0.90, 0.55, 0.20) x 255 within 1; the same view with the
// link's role set to scoop shows the scoop's grey there instead.
TEST(RendererTest, ArmLinksAreDrawn) {
  const sim::ArmGeometry arm =
      sim::ArmGeometry::FromUrdf(std::string(SCOOPSIM_SOURCE_DIR) + "/assets/lander_arm.urdf");
  ASSERT_EQ(arm.dof(), 6);
  ASSERT_EQ(arm.parts(), 5);  // l_shou .. l_hand (with the grinder); l_scoop is the DEM's mesh
  const double q[6] = {0, 0.8537, -1.5707, 0.7171, 1.5, 0};
  sim::WorldView view;
  dem::Particles none;
  view.particles = &none;
  arm.AddToView(q, sim::ArmBase{{1, 2, 0.5}, 0.3}, &view);
  ASSERT_EQ(view.meshes.size(), 5u);
  const int dist = 2;  // l_dist: its box is centred at (0.293, 0, -0.075) in the body frame
  ASSERT_EQ(arm.mesh(dist).name, "l_dist");
  const dem::Vec3 centre = dem::Apply(view.meshes[dist].pose, {0.293, 0, -0.075});
  RenderSettings settings = PlainSettings();
  settings.shading = false;
  settings.camera.target = centre;
  settings.camera.position = centre + dem::Vec3{0.2, -0.4, 0.2};
  const Image& image = SharedRenderer().Render(view, settings);
  const Rgba8 c = image.At(settings.camera.width / 2, settings.camera.height / 2);
  EXPECT_NEAR(c.r, 0.90 * 255, 1);
  EXPECT_NEAR(c.g, 0.55 * 255, 1);
  EXPECT_NEAR(c.b, 0.20 * 255, 1);
  for (sim::MeshView& m : view.meshes) m.role = sim::MeshRole::kScoop;
  const Rgba8 grey = SharedRenderer()
                         .Render(view, settings)
                         .At(settings.camera.width / 2, settings.camera.height / 2);
  EXPECT_NEAR(grey.r, 0.74 * 255, 1);
  EXPECT_NEAR(grey.b, 0.80 * 255, 1);
}

// The caption and the fault line sit on a light plate (kPlate, 85% opaque) that keeps them
// readable over the orange links: an arm link filling the whole frame, a fault latched. Inside the
// plate, away from the glyphs, every channel is above 200 (kPlate over orange: 247, 219, 219 within
// rounding), where the link elsewhere is orange (blue 0.20 x 255 within 1); the fault's red glyphs
// are on the plate. So is the torque bars' block.
TEST(RendererTest, CaptionAndFaultLineSitOnALightPlate) {
  dem::TriangleMesh link;
  link.vertices = {{-5, -5, 0}, {5, -5, 0}, {5, 5, 0}, {-5, 5, 0}};
  link.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 2, 1}, {0, 3, 2}};
  sim::WorldView view;
  dem::Particles none;
  view.particles = &none;
  view.meshes.push_back({&link, dem::Pose{}, sim::MeshRole::kArmLink});
  view.faults = "JOINT_TORQUE_LIMIT";
  view.joints = {{"j_a", 1.0, 10.0}};
  RenderSettings settings = PlainSettings();
  settings.shading = false;
  settings.overlays = true;
  settings.camera.position = {0, 0, 1};
  settings.camera.target = {0, 0, 0};
  settings.camera.up = {0, 1, 0};
  const Image& image = SharedRenderer().Render(view, settings);
  const int s = 2;  // the font scale at 480 rows
  const Rgba8 link_colour = image.At(image.width() / 2, image.height() / 2);
  EXPECT_NEAR(link_colour.b, 0.20 * 255, 1);
  for (const auto& [x, y] :
       {std::pair{9 * s, 8 * s}, std::pair{9 * s, 10 * s + 2 * kGlyphHeight * s},
        std::pair{9 * s, image.height() - 10 * s - (kGlyphHeight + 2) * s}}) {
    const Rgba8 c = image.At(x, y);
    EXPECT_GT(c.r, 200) << x << "," << y;
    EXPECT_GT(c.g, 200) << x << "," << y;
    EXPECT_GT(c.b, 200) << x << "," << y;
  }
  int red = 0;
  for (int y = 10 * s + kGlyphHeight * s; y < 10 * s + 2 * kGlyphHeight * s; ++y)
    for (int x = 12 * s; x < 12 * s + TextWidth("FAULT JOINT_TORQUE_LIMIT", s); ++x)
      red += image.At(x, y) == kMarginOver;
  EXPECT_GT(red, 100);
}

// The caption's time is the view's, on the run's one clock (README "One clock": the state's, from
// the pour), as every dataset and stderr line gives it: exact to the 5 decimals shown.
TEST(RendererTest, CaptionShowsTheRunsClock) {
  sim::WorldView view;
  view.time = 3.25;
  EXPECT_EQ(Caption(view), "t = 3.25000 s");
  view.pass = 1;
  EXPECT_EQ(Caption(view).rfind("t = 3.25000 s   pass 1", 0), 0u) << Caption(view);
}

// Every camera preset a scene may name (sim::kRenderCameraPresets) exists here, and frames the
// box: all eight corners project inside the image.
TEST(CameraTest, PresetsFrameTheBox) {
  const dem::Vec3 lo{0, 0, 0}, hi{0.4, 0.3, 0.15};
  for (const char* name : sim::kRenderCameraPresets) {
    Camera camera;
    ASSERT_TRUE(ApplyCameraPreset(name, lo, hi, &camera)) << name;
    const Pinhole pinhole(camera);
    for (int k = 0; k < 8; ++k) {
      const dem::Vec3 corner{(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z};
      double col = 0, row = 0;
      pinhole.Project(corner, &col, &row);
      EXPECT_GE(col, 0) << name;
      EXPECT_LE(col, camera.width) << name;
      EXPECT_GE(row, 0) << name;
      EXPECT_LE(row, camera.height) << name;
    }
  }
  EXPECT_EQ(CameraPresetNames().size(), std::size(sim::kRenderCameraPresets));
  Camera camera;
  EXPECT_FALSE(ApplyCameraPreset("nowhere", lo, hi, &camera));
}

// The arm preset frames the container and every mesh of the view: an "arm" reaching 1.6 m out of
// a 0.32 m box and 0.6 m above it (the lander's arm beside its trench) projects wholly inside the
// image, its base included, where trench_oblique (the box alone) leaves the base out. The scoop
// preset frames a cube of kScoopFrame around the scoop wherever it is, and follows it.
TEST(CameraTest, ArmPresetFramesTheWholeArmAndScoopPresetFollowsTheScoop) {
  sim::WorldView view;
  view.box_min = {0, 0, 0};
  view.box_max = {0.32, 0.19, 0.15};
  dem::TriangleMesh arm, scoop;
  arm.vertices = {{-1.3, 0.27, 0.2}, {-0.8, 0.27, 0.75}, {0.1, 0.1, 0.3}};
  arm.triangles = {{0, 1, 2}};
  scoop.vertices = {{-0.05, -0.04, 0}, {0.05, 0.04, 0.08}, {0.05, -0.04, 0}};
  scoop.triangles = {{0, 1, 2}};
  dem::Pose at;
  at.position = {0.15, 0.095, 0.09};
  view.meshes.push_back({&arm, dem::Pose{}, sim::MeshRole::kArmLink});
  view.meshes.push_back({&scoop, at, sim::MeshRole::kScoop});
  auto inside = [](const Camera& camera, const dem::Vec3& x) {
    double col = 0, row = 0;
    Pinhole(camera).Project(x, &col, &row);
    return col >= 0 && col <= camera.width && row >= 0 && row <= camera.height;
  };
  dem::Vec3 lo, hi;
  PresetBounds("arm", view, &lo, &hi);
  Camera camera;
  ASSERT_TRUE(ApplyCameraPreset("arm", lo, hi, &camera));
  for (const dem::Vec3& v : arm.vertices) EXPECT_TRUE(inside(camera, v)) << v.x;
  for (int k = 0; k < 8; ++k) {
    const dem::Vec3 corner{(k & 1) ? view.box_max.x : 0.0, (k & 2) ? view.box_max.y : 0.0,
                           (k & 4) ? view.box_max.z : 0.0};
    EXPECT_TRUE(inside(camera, corner)) << k;
  }
  PresetBounds("trench_oblique", view, &lo, &hi);
  EXPECT_EQ(lo.x, 0.0);
  EXPECT_EQ(hi.z, 0.15);
  Camera box = camera;
  ApplyCameraPreset("trench_oblique", lo, hi, &box);
  EXPECT_FALSE(inside(box, arm.vertices[0]));

  // The scoop's cube: centred on the scoop mesh's world extent, kScoopFrame a side.
  PresetBounds("scoop", view, &lo, &hi);
  EXPECT_NEAR(0.5 * (lo.x + hi.x), 0.15, 1e-12);
  EXPECT_NEAR(0.5 * (lo.z + hi.z), 0.09 + 0.04, 1e-12);
  EXPECT_NEAR(hi.y - lo.y, kScoopFrame, 1e-12);
  view.meshes[1].pose.position.x += 0.1;
  dem::Vec3 lo2, hi2;
  PresetBounds("scoop", view, &lo2, &hi2);
  EXPECT_NEAR(lo2.x - lo.x, 0.1, 1e-12);
}

}  // namespace
}  // namespace render
