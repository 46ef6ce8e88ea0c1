// URDF -> ArmModel with urdfdom. The only file of arm/ that sees urdfdom.
#include "arm/arm_model.h"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <regex>
#include <sstream>

#include "arm/internal_urdf_text.h"

namespace arm {

const char* JointTypeName(JointType type) {
  return type == JointType::kRevolute ? "revolute" : "continuous";
}

double ArmModel::MovingMass() const {
  double mass = 0;
  for (size_t i = 1; i < bodies.size(); ++i) mass += bodies[i].inertial.mass;
  return mass;
}

int ArmModel::JointIndex(const std::string& name) const {
  for (size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

bool ArmModel::FindLink(const std::string& link, int* body, Eigen::Isometry3d* in_body) const {
  for (size_t b = 0; b < bodies.size(); ++b) {
    for (const Frame& f : bodies[b].frames) {
      if (f.link == link) {
        if (body) *body = static_cast<int>(b);
        if (in_body) *in_body = f.in_body;
        return true;
      }
    }
  }
  return false;
}

namespace {

// urdfdom reports through console_bridge; its messages are caught here and put into ours.
class CaptureHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) errors.push_back(text);
  }
  std::vector<std::string> errors;  // in the order urdfdom logged them
};

// Builds the one-line messages: "SOURCE:LINE: ELEMENT: expected ..., got ...".
class Reporter {
 public:
  // The text is read once, here (UrdfIndex): a message's line is looked up, not searched for.
  Reporter(const std::string& source, const std::string& text)
      : source_(source), text_(text), index_(text) {}
  [[noreturn]] void Fail(const std::string& tag, const std::string& name,
                         const std::string& element, const std::string& what) const {
    const int line = tag.empty() ? 0 : Line(tag, name);
    std::ostringstream out;
    out << source_;
    if (line > 0) out << ':' << line;
    out << ": " << element << ": " << what;
    throw ArmModelError(out.str());
  }
  // 1-based line of the first `<tag ... name="name"` in the text, or 0.
  int Line(const std::string& tag, const std::string& name) const { return index_.Line(tag, name); }
  // The text of attribute `attr` of the first <child> inside <link name="link">, as written
  // ("" when there is none): urdfdom reads a value it cannot parse as 0.
  std::string Raw(const std::string& link, const std::string& child,
                  const std::string& attr) const {
    const auto [begin, end] = index_.Span("link", link);
    if (begin == std::string::npos) return "";
    return AttributeIn(text_, begin, end, child, attr);
  }

 private:
  const std::string& source_;
  const std::string& text_;
  const UrdfIndex index_;
};

std::string Num(double v) {
  std::ostringstream out;
  out.precision(9);
  out << v;
  return out.str();
}

Eigen::Isometry3d ToIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  t.linear() =
      Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z)
          .normalized()
          .toRotationMatrix();
  return t;
}

// A link's own inertial in its link frame (CoM, inertia about the CoM in link axes).
Inertial LinkInertial(const urdf::Inertial& in) {
  Inertial out;
  out.mass = in.mass;
  const Eigen::Isometry3d frame = ToIsometry(in.origin);
  Eigen::Matrix3d i;
  i << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  out.com = frame.translation();
  out.inertia = frame.linear() * i * frame.linear().transpose();
  return out;
}

// Checks a link's inertial values as written: urdfdom reads "abc", "" and "nan" as 0, which the
// checks of CheckInertial would report as "got 0" (and a fixed link's, or the base's, would pass
// unseen). Called for every link with an <inertial>, frames and the base included.
void CheckWrittenNumbers(const Reporter& report, const std::string& link) {
  const std::pair<const char*, const char*> written[] = {
      {"mass", "value"},  {"inertia", "ixx"}, {"inertia", "ixy"}, {"inertia", "ixz"},
      {"inertia", "iyy"}, {"inertia", "iyz"}, {"inertia", "izz"}};
  for (const auto& [child, attr] : written) {
    std::string raw = report.Raw(link, child, attr);
    raw.erase(0, raw.find_first_not_of(" \t\n"));
    raw.erase(raw.find_last_not_of(" \t\n") + 1);
    if (raw.empty()) continue;
    char* end = nullptr;
    const double value = std::strtod(raw.c_str(), &end);
    if (end == raw.c_str() || *end != '\0') {
      report.Fail("link", link, "link '" + link + "' <" + child + " " + attr + ">",
                  "expected a number, got '" + raw + "'");
    }
    // urdfdom reads "nan" and "inf" as 0 too.
    if (!std::isfinite(value)) {
      report.Fail("link", link, "link '" + link + "' <" + child + " " + attr + ">",
                  "expected a finite number, got '" + raw + "'");
    }
  }
}

// Checks a link's inertial: finite, mass > 0, inertia symmetric positive definite with principal
// moments obeying the triangle inequality (a real body's do).
void CheckInertial(const Reporter& report, const std::string& link, const urdf::Inertial& in) {
  const double values[] = {in.mass, in.ixx, in.ixy, in.ixz, in.iyy, in.iyz, in.izz};
  for (double v : values) {
    if (!std::isfinite(v)) {
      report.Fail("link", link, "link '" + link + "' <inertial>",
                  "expected finite mass and inertia, got " + Num(v));
    }
  }
  if (in.mass <= 0) {
    report.Fail("link", link, "link '" + link + "' <mass>",
                "expected a mass > 0 kg, got " + Num(in.mass));
  }
  Eigen::Matrix3d i;
  i << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  const Eigen::Vector3d m = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(i).eigenvalues();
  if (m.minCoeff() <= 0) {
    report.Fail("link", link, "link '" + link + "' <inertia>",
                "expected a positive-definite inertia, got principal moments " + Num(m[0]) + " " +
                    Num(m[1]) + " " + Num(m[2]) + " kg m^2");
  }
  const double slack = 1e-9 * m.sum();
  if (m[0] + m[1] < m[2] - slack) {
    report.Fail("link", link, "link '" + link + "' <inertia>",
                "expected principal moments obeying the triangle inequality (I1 + I2 >= I3), "
                "got " +
                    Num(m[0]) + " " + Num(m[1]) + " " + Num(m[2]) + " kg m^2");
  }
}

// Adds a link's inertial (already in the body frame) to a body's.
void Merge(Inertial* body, const Inertial& part) {
  const double mass = body->mass + part.mass;
  if (mass <= 0) return;
  const Eigen::Vector3d com = (body->mass * body->com + part.mass * part.com) / mass;
  auto shifted = [&com](const Inertial& x) {
    const Eigen::Vector3d d = x.com - com;
    return Eigen::Matrix3d(
        x.inertia + x.mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose()));
  };
  body->inertia = shifted(*body) + shifted(part);
  body->mass = mass;
  body->com = com;
}

Inertial Transformed(const Inertial& in, const Eigen::Isometry3d& t) {
  Inertial out = in;
  out.com = t * in.com;
  out.inertia = t.linear() * in.inertia * t.linear().transpose();
  return out;
}

void AddShapes(const urdf::Link& link, const Eigen::Isometry3d& in_body,
               const std::string& base_dir, std::vector<Shape>* shapes) {
  auto add = [&](const urdf::GeometrySharedPtr& g, const urdf::Pose& origin, bool collision) {
    if (!g) return;
    Shape s;
    s.link = link.name;
    s.collision = collision;
    s.origin = in_body * ToIsometry(origin);
    switch (g->type) {
      case urdf::Geometry::SPHERE:
        s.kind = Shape::Kind::kSphere;
        s.size = {static_cast<const urdf::Sphere&>(*g).radius, 0, 0};
        break;
      case urdf::Geometry::BOX: {
        const urdf::Vector3& d = static_cast<const urdf::Box&>(*g).dim;
        s.kind = Shape::Kind::kBox;
        s.size = {d.x, d.y, d.z};
        break;
      }
      case urdf::Geometry::CYLINDER: {
        const auto& c = static_cast<const urdf::Cylinder&>(*g);
        s.kind = Shape::Kind::kCylinder;
        s.size = {c.radius, c.length, 0};
        break;
      }
      case urdf::Geometry::MESH: {
        const auto& m = static_cast<const urdf::Mesh&>(*g);
        s.kind = Shape::Kind::kMesh;
        s.size = {m.scale.x, m.scale.y, m.scale.z};
        const std::filesystem::path file(m.filename);
        s.mesh_path = (base_dir.empty() || file.is_absolute())
                          ? m.filename
                          : (std::filesystem::path(base_dir) / file).lexically_normal().string();
        break;
      }
    }
    shapes->push_back(s);
  };
  for (const auto& v : link.visual_array) add(v->geometry, v->origin, false);
  for (const auto& c : link.collision_array) add(c->geometry, c->origin, true);
}

std::string TypeName(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE:
      return "revolute";
    case urdf::Joint::CONTINUOUS:
      return "continuous";
    case urdf::Joint::PRISMATIC:
      return "prismatic";
    case urdf::Joint::FLOATING:
      return "floating";
    case urdf::Joint::PLANAR:
      return "planar";
    case urdf::Joint::FIXED:
      return "fixed";
    default:
      return "unknown";
  }
}

// The most URDF text read: a URDF names its meshes, it does not hold them (the lander's is 7 kB).
constexpr std::uintmax_t kMaxUrdfBytes = std::uintmax_t{64} << 20;

std::string TooLarge(std::uintmax_t bytes) {
  std::ostringstream out;
  out.precision(3);
  out << "expected at most " << (kMaxUrdfBytes >> 20) << " MiB of URDF, got "
      << static_cast<double>(bytes) / (1 << 20) << " MiB";
  return out.str();
}

// Checks that the joints make the links a tree: no link the child of two joints (urdfdom keeps
// the last, by name, without a word) and no link its own ancestor (urdfdom accepts a loop cut off
// from the root; walking up from a link in it never ends). Names the joint at fault: the second
// parent in the file, or the loop's first joint in the file. In time linear in the joints.
void CheckTree(const Reporter& report, const urdf::ModelInterface& urdf) {
  using Placed = std::pair<int, const urdf::Joint*>;  // (line, joint)
  const auto file_order = [](const Placed& a, const Placed& b) {
    return a.first != b.first ? a.first < b.first : a.second->name < b.second->name;
  };
  std::vector<Placed> joints;
  for (const auto& [name, joint] : urdf.joints_)
    joints.emplace_back(report.Line("joint", name), joint.get());
  std::sort(joints.begin(), joints.end(), file_order);
  std::map<std::string, const urdf::Joint*> parent_joint;  // link -> the joint it is child of
  for (const auto& [line, j] : joints) {
    const auto [it, first] = parent_joint.emplace(j->child_link_name, j);
    if (!first) {
      report.Fail("joint", j->name, "joint '" + j->name + "' <child>",
                  "expected a link with one parent joint (the links a tree), got link '" +
                      j->child_link_name + "', already the child of joint '" + it->second->name +
                      "'");
    }
  }
  // Walk up from each link until a link already walked: one seen in this walk closes a loop.
  std::map<std::string, int> walk_of;  // link -> the walk that reached it (1, 2, ...)
  int walk = 0;
  for (const auto& [line, j] : joints) {
    ++walk;
    std::string link = j->child_link_name;
    while (!walk_of.count(link)) {
      walk_of[link] = walk;
      const auto up = parent_joint.find(link);
      if (up == parent_joint.end()) break;
      link = up->second->parent_link_name;
    }
    if (walk_of.at(link) != walk || !parent_joint.count(link)) continue;
    // `link` is on a loop: its joints, the first in the file named.
    std::vector<Placed> loop;
    std::string at = link;
    do {
      const urdf::Joint* up = parent_joint.at(at);
      loop.emplace_back(report.Line("joint", up->name), up);
      at = up->parent_link_name;
    } while (at != link);
    std::sort(loop.begin(), loop.end(), file_order);
    std::string names;
    for (const auto& [l, up] : loop) names += (names.empty() ? "" : ", ") + up->name;
    const urdf::Joint& first = *loop.front().second;
    report.Fail("joint", first.name, "joint '" + first.name + "' <parent>",
                "expected the links to form a tree (no link its own ancestor), got a loop through "
                "joints " +
                    names);
  }
}

}  // namespace

ArmModel Derated(const ArmModel& model, const std::vector<double>& factors) {
  ArmModel derated = model;
  for (size_t i = 0; i < derated.joints.size() && i < factors.size(); ++i)
    derated.joints[i].effort *= factors[i];
  return derated;
}

ArmModel LoadArmModel(const std::string& path, const std::string& tip_link) {
  std::error_code ec;
  // A folder opens as a stream that reads nothing (urdfdom: "Error document empty").
  if (std::filesystem::is_directory(path, ec))
    throw ArmModelError(path + ": URDF file: expected a readable file, got a folder");
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw ArmModelError(path + ": URDF file: expected a readable file, got " +
                        std::strerror(errno));
  }
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > kMaxUrdfBytes) throw ArmModelError(path + ": URDF file: " + TooLarge(size));
  std::ostringstream text;
  text << in.rdbuf();
  const std::string dir = std::filesystem::path(path).parent_path().string();
  return ParseArmModel(text.str(), path, tip_link, dir.empty() ? "." : dir);
}

ArmModel ParseArmModel(const std::string& urdf_text, const std::string& source,
                       const std::string& tip_link, const std::string& base_dir) {
  if (urdf_text.size() > kMaxUrdfBytes)
    throw ArmModelError(source + ": URDF text: " + TooLarge(urdf_text.size()));
  const Reporter report(source, urdf_text);

  // urdfdom: its error text goes into our message instead of onto stderr. console_bridge's
  // handler is process-wide, hence the lock.
  urdf::ModelInterfaceSharedPtr urdf;
  {
    static std::mutex mutex;
    std::lock_guard<std::mutex> lock(mutex);
    CaptureHandler capture;
    console_bridge::useOutputHandler(&capture);
    urdf = urdf::parseURDF(urdf_text);
    console_bridge::restorePreviousOutputHandler();
    if (!urdf) {
      const std::string got = capture.errors.empty() ? "unparsable input" : capture.errors[0];
      // A structural error names the element at fault, as "joint [NAME]" or "link 'NAME'", in
      // one of urdfdom's messages: the first such element the file has is the one reported.
      static const std::regex named("\\b(joint|link)\\s*(?:\\[([^\\]]*)\\]|'([^']*)')",
                                    std::regex::icase);
      for (const std::string& error : capture.errors) {
        for (std::sregex_iterator m(error.begin(), error.end(), named), end; m != end; ++m) {
          std::string tag = (*m)[1].str();
          std::transform(tag.begin(), tag.end(), tag.begin(),
                         [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
          const std::string name = (*m)[(*m)[2].matched ? 2 : 3].str();
          if (report.Line(tag, name) > 0) {
            report.Fail(tag, name, tag + " '" + name + "'",
                        "expected an element urdfdom can build into a URDF model, got: " + got);
          }
        }
      }
      throw ArmModelError(source + ": <robot>: expected a URDF (XML with one <robot> element), " +
                          "got: " + got);
    }
  }

  // A loop of joints (refused by CheckTree) makes urdfdom's links own each other through their
  // child_links (shared pointers): those are cut when the model goes, on every path out of here,
  // so that a refused URDF leaks nothing (LeakSanitizer found it).
  struct CutChildLinks {
    urdf::ModelInterface* model;
    ~CutChildLinks() {
      for (auto& named : model->links_) named.second->child_links.clear();
    }
  } cut_child_links{urdf.get()};

  ArmModel model;
  model.source = source;
  model.robot_name = urdf->getName();
  model.tip_link = tip_link;

  CheckTree(report, *urdf);
  const urdf::LinkConstSharedPtr root = urdf->getRoot();
  const urdf::LinkConstSharedPtr tip = urdf->getLink(tip_link);
  if (!tip) {
    report.Fail("robot", model.robot_name, "<robot name=\"" + model.robot_name + "\">",
                "expected a link named '" + tip_link + "' (the scoop, the chain's tip), got none");
  }

  // The chain: movable joints from the tip up to the root, then reversed.
  std::vector<urdf::JointConstSharedPtr> chain;
  for (urdf::LinkConstSharedPtr l = tip; l != root; l = l->getParent()) {
    const urdf::JointConstSharedPtr& j = l->parent_joint;
    if (j->type == urdf::Joint::FIXED) continue;
    if (j->type != urdf::Joint::REVOLUTE && j->type != urdf::Joint::CONTINUOUS) {
      report.Fail("joint", j->name, "joint '" + j->name + "' type",
                  "expected revolute, continuous or fixed on the chain " + root->name + " -> " +
                      tip_link + ", got " + TypeName(j->type));
    }
    chain.push_back(j);
  }
  std::reverse(chain.begin(), chain.end());

  // Bodies: the root, then each chain joint's child link.
  std::map<std::string, int> body_of_link;  // chain links -> body index
  body_of_link[root->name] = 0;
  model.bodies.resize(chain.size() + 1);
  model.bodies[0].link = root->name;
  for (size_t i = 0; i < chain.size(); ++i) {
    model.bodies[i + 1].link = chain[i]->child_link_name;
    body_of_link[chain[i]->child_link_name] = static_cast<int>(i + 1);
  }

  // Every link goes to the body of its nearest chain ancestor (or itself), through fixed (or
  // held) joints; its inertial and shapes are merged there.
  std::vector<urdf::LinkSharedPtr> links;
  urdf->getLinks(links);
  std::sort(
      links.begin(), links.end(),
      [](const urdf::LinkSharedPtr& a, const urdf::LinkSharedPtr& b) { return a->name < b->name; });
  for (const urdf::LinkSharedPtr& link : links) {
    Eigen::Isometry3d in_body = Eigen::Isometry3d::Identity();
    urdf::LinkConstSharedPtr l = link;
    while (!body_of_link.count(l->name)) {
      const urdf::JointConstSharedPtr& j = l->parent_joint;
      if (j->type == urdf::Joint::FLOATING || j->type == urdf::Joint::PLANAR ||
          j->type == urdf::Joint::UNKNOWN) {
        report.Fail("joint", j->name, "joint '" + j->name + "' type",
                    "expected fixed, revolute, continuous or prismatic off the chain (held at "
                    "zero), got " +
                        TypeName(j->type));
      }
      if (j->type != urdf::Joint::FIXED && l == link) model.held_joints.push_back(j->name);
      in_body = ToIsometry(j->parent_to_joint_origin_transform) * in_body;
      l = l->getParent();
    }
    const int b = body_of_link.at(l->name);
    Body& body = model.bodies[b];
    const bool is_body_link = (l == link);
    const bool moving = b > 0;
    // A merged link without an <inertial> or of at most kFrameMass is a frame (arm_model.h).
    if (link->inertial) CheckWrittenNumbers(report, link->name);
    const double mass = link->inertial ? link->inertial->mass : 0;
    const bool is_frame = !is_body_link && (!link->inertial || (mass >= 0 && mass <= kFrameMass));
    if (!link->inertial) {
      if (moving && is_body_link) {
        report.Fail("link", link->name, "link '" + link->name + "'",
                    "expected an <inertial> on every link a chain joint moves (" + root->name +
                        " -> " + tip_link + "), got none");
      }
    } else if (moving && !is_frame) {
      CheckInertial(report, link->name, *link->inertial);
      if (is_body_link && mass <= kFrameMass) {
        report.Fail("link", link->name, "link '" + link->name + "' <mass>",
                    "expected a mass > " + Num(kFrameMass) +
                        " kg on a link a chain joint moves (a lighter link is a frame, allowed "
                        "on fixed joints only), got " +
                        Num(mass));
      }
    }
    if (link->inertial && !is_frame) {
      Merge(&body.inertial, Transformed(LinkInertial(*link->inertial), in_body));
    }
    if (!is_body_link) {
      const urdf::Joint& j = *link->parent_joint;
      model.merges.push_back({link->name, body.link, j.name,
                              j.type == urdf::Joint::FIXED ? "fixed" : "held", is_frame,
                              link->inertial != nullptr, mass});
    }
    Frame frame{link->name, in_body};
    if (is_body_link) {
      body.frames.insert(body.frames.begin(), frame);
    } else {
      body.frames.push_back(frame);
    }
    AddShapes(*link, in_body, base_dir, &body.shapes);
  }
  // Held joints were collected once per link below them; keep each once, in order.
  std::sort(model.held_joints.begin(), model.held_joints.end());
  model.held_joints.erase(std::unique(model.held_joints.begin(), model.held_joints.end()),
                          model.held_joints.end());

  // Chain joints: origins from the parent body's frame, limits, dynamics.
  for (size_t i = 0; i < chain.size(); ++i) {
    const urdf::Joint& j = *chain[i];
    Joint out;
    out.name = j.name;
    out.line = report.Line("joint", j.name);
    out.type = j.type == urdf::Joint::REVOLUTE ? JointType::kRevolute : JointType::kContinuous;
    int parent_body = 0;
    Eigen::Isometry3d parent_in_body = Eigen::Isometry3d::Identity();
    model.FindLink(j.parent_link_name, &parent_body, &parent_in_body);
    if (parent_body != static_cast<int>(i)) {
      report.Fail("joint", j.name, "joint '" + j.name + "'",
                  "expected the chain's joints in order from the root, got a parent off it");
    }
    out.origin = parent_in_body * ToIsometry(j.parent_to_joint_origin_transform);
    const Eigen::Vector3d axis(j.axis.x, j.axis.y, j.axis.z);
    if (!(axis.norm() > 1e-9) || !axis.allFinite()) {
      report.Fail("joint", j.name, "joint '" + j.name + "' <axis>",
                  "expected a non-zero axis, got " + Num(axis.x()) + " " + Num(axis.y()) + " " +
                      Num(axis.z()));
    }
    out.axis = axis.normalized();
    const std::string element = "joint '" + j.name + "' <limit>";
    if (!j.limits) {
      report.Fail("joint", j.name, element,
                  "expected <limit effort=... velocity=...> (the motor's saturation), got none");
    }
    out.effort = j.limits->effort;
    out.velocity = j.limits->velocity;
    if (!(out.effort > 0) || !std::isfinite(out.effort)) {
      report.Fail("joint", j.name, element,
                  "expected effort (the torque limit) > 0 N m, got " + Num(out.effort));
    }
    if (!(out.velocity > 0) || !std::isfinite(out.velocity)) {
      report.Fail("joint", j.name, element,
                  "expected velocity (the velocity limit) > 0 rad/s, got " + Num(out.velocity));
    }
    if (out.type == JointType::kRevolute) {
      out.has_position_limits = true;
      out.lower = j.limits->lower;
      out.upper = j.limits->upper;
      if (!(out.lower < out.upper) || !std::isfinite(out.lower) || !std::isfinite(out.upper)) {
        report.Fail(
            "joint", j.name, element,
            "expected lower < upper, got lower " + Num(out.lower) + " upper " + Num(out.upper));
      }
    }
    if (j.dynamics) {
      out.damping = j.dynamics->damping;
      out.friction = j.dynamics->friction;
      if (!(out.damping >= 0) || !(out.friction >= 0) || !std::isfinite(out.damping) ||
          !std::isfinite(out.friction)) {
        report.Fail("joint", j.name, "joint '" + j.name + "' <dynamics>",
                    "expected damping >= 0 and friction >= 0, got damping " + Num(out.damping) +
                        " friction " + Num(out.friction));
      }
    }
    model.joints.push_back(out);
  }
  if (model.joints.empty()) {
    report.Fail("link", tip_link, "link '" + tip_link + "'",
                "expected at least one revolute or continuous joint between " + root->name +
                    " and it, got none");
  }
  return model;
}

}  // namespace arm
