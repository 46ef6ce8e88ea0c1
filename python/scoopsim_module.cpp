// scoopsim._scoopsim: the compiled half of the Python module scoopsim (docs/python.md), thin over
// the rooms' public headers. The package python/scoopsim/__init__.py re-exports it with the pure
// Python parts (open_run, Table.query's broadcasting). Units are SI, as inside; quaternions w x y
// z.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <csignal>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "arm/arm_model.h"
#include "arm/kinematics.h"
#include "sim/files/arm_geometry.h"
#include "sim/files/h5_output.h"
#include "sim/files/wrench_table.h"
#include "sim/input/exit_status.h"
#include "sim/input/scene.h"
#include "sim/loop/arm_driver.h"
#include "sim/loop/dig.h"
#include "sim/loop/external_driver.h"
#include "sim/loop/preflight.h"
#include "sim/loop/world.h"
#include "sim/studies/commands.h"

namespace py = pybind11;

namespace {

static_assert(sizeof(dem::Vec3) == 3 * sizeof(double), "Vec3 arrays are viewed as (n, 3) doubles");

// The scene's --set overrides from a dict {key: value} (value as str(), so 0.02, True and
// [1, 2] read as YAML) or a list of "KEY=VALUE" strings.
std::vector<std::string> Sets(const py::object& overrides) {
  std::vector<std::string> sets;
  if (overrides.is_none()) return sets;
  if (py::isinstance<py::dict>(overrides)) {
    for (const auto& item : py::reinterpret_borrow<py::dict>(overrides)) {
      const py::object value = py::reinterpret_borrow<py::object>(item.second);
      std::string text = py::str(value);
      if (py::isinstance<py::bool_>(value)) text = value.cast<bool>() ? "true" : "false";
      sets.push_back(py::str(item.first).cast<std::string>() + "=" + text);
    }
    return sets;
  }
  for (const py::handle item : overrides) sets.push_back(py::str(item).cast<std::string>());
  return sets;
}

// The scene as `scoopsim run` reads it: LoadScene with the overrides, then Preflight (what
// follows from the values together and the files they name), an error about an override naming
// the --set as the CLI's does (sim::NamingSet).
sim::Scene Load(const std::string& path, const py::object& overrides) {
  const std::vector<std::string> sets = Sets(overrides);
  sim::Scene scene = sim::LoadScene(path, sets);
  try {
    sim::Preflight(&scene, sim::Work::kRun);
  } catch (const sim::InputError& e) {
    throw sim::NamingSet(e, sets);
  }
  return scene;
}

// While a long call runs in C++ with the GIL released (a pour, scoopsim.run), SIGINT and SIGTERM
// go to the loop's own stop handlers (sim::InstallStopHandlers: the run closes its output and
// stops); Python's handlers are put back afterwards, and a stop becomes KeyboardInterrupt.
class StopHandlers {
 public:
  StopHandlers() {
    sigaction(SIGINT, nullptr, &old_int_);
    sigaction(SIGTERM, nullptr, &old_term_);
    sim::ClearStopRequest();
    sim::InstallStopHandlers();
  }
  ~StopHandlers() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
    sim::ClearStopRequest();
  }
  // Raises KeyboardInterrupt when a signal asked to stop (the GIL held).
  static void RaiseIfStopped(int status) {
    if (status == sim::kExitStopped || sim::StopRequested()) {
      PyErr_SetNone(PyExc_KeyboardInterrupt);
      throw py::error_already_set();
    }
  }

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

// A (n, 3) or (n,) read-only view into a World's particle arrays, keeping the World alive.
template <typename T>
py::array View(const std::vector<T>& data, int columns, py::handle base, bool copy) {
  const py::ssize_t n = static_cast<py::ssize_t>(data.size());
  const double* ptr = reinterpret_cast<const double*>(data.data());
  py::array a = columns == 1
                    ? py::array_t<double>({n}, {sizeof(double)}, ptr, base)
                    : py::array_t<double>({n, py::ssize_t{columns}},
                                          {sizeof(double) * columns, sizeof(double)}, ptr, base);
  if (copy) return py::array_t<double>(a.attr("copy")());
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

py::array_t<double> Six(const dem::Vec3& f, const dem::Vec3& t) {
  py::array_t<double> a(6);
  double* d = a.mutable_data();
  for (int i = 0; i < 3; ++i) {
    d[i] = f[i];
    d[3 + i] = t[i];
  }
  return a;
}

// A World set up as `scoopsim run` sets it up (sim::RunScene), without an output file: the
// scene's driver, the bed loaded or poured, the dig started.
class PyWorld {
 public:
  // driver "scene": the scene's own (sim::MakeScoopDriver); "python": the scoop where
  // set_scoop_pose puts it (sim::ExternalPoseDriver; the scene needs a dig for its scoop).
  PyWorld(sim::Scene scene, int threads, const std::string& driver_kind,
          const py::object& scoop_motion, bool adaptive_threads) {
    sim::Preflight(&scene, sim::Work::kRun);
    std::unique_ptr<sim::ScoopDriver> driver;
    if (driver_kind == "python") {
      if (!scene.dig.enabled)
        throw sim::InputError(scene.path +
                              ": World(driver='python'): the scene needs a dig (its scoop)");
      auto external = std::make_unique<sim::ExternalPoseDriver>(scene);
      external_ = external.get();
      if (!scoop_motion.is_none()) external_->SetMotion(Motion(scoop_motion));
      driver = std::move(external);
    } else if (driver_kind == "scene") {
      driver = sim::MakeScoopDriver(scene, /*announce=*/false);
      arm_ = dynamic_cast<sim::ArmDriver*>(driver.get());
    } else {
      throw py::value_error("World: driver: expected 'scene' or 'python', got " + driver_kind);
    }
    const bool needs_bed = !driver || driver->OwnStep() == 0;
    world_ = std::make_unique<sim::World>(scene, threads > 0 ? threads : scene.threads);
    // As `scoopsim run` (RunOptions::adaptive_threads): fewer workers while timing shows fewer
    // are faster (a busy core); the same results either way.
    world_->mutable_system().set_adaptive_threads(adaptive_threads);
    if (needs_bed) {
      if (!scene.bed.file.empty()) {
        world_->LoadBed(scene.bed.file);
      } else {
        int status = 0;
        {
          StopHandlers stop;
          py::gil_scoped_release release;
          sim::SettleReport report;
          status = world_->Pour(/*quiet=*/true, &report);
          if (status == sim::kExitStopped) {
            py::gil_scoped_acquire acquire;
            StopHandlers::RaiseIfStopped(status);
          }
        }
        if (status != sim::kExitOk)
          throw std::runtime_error(scene.path + ": the bed's pour failed (exit status " +
                                   std::to_string(status) + ")");
      }
    }
    if (driver) {
      world_->StartDig(std::move(driver));
    } else {
      world_->StartPlainRun();
    }
  }

  // Up to n steps, fewer when the run is done (a dig's last pass) or a step is unhealthy
  // (RuntimeError). The GIL is released; every kCheckEvery steps it is taken back to look for a
  // signal (Ctrl-C: KeyboardInterrupt, the world left between two steps). Returns steps done.
  int64_t Step(int64_t n) {
    constexpr int64_t kCheckEvery = 64;
    int64_t done = 0;
    while (done < n && !world_->Done()) {
      dem::StepStatus status;
      const int64_t chunk = std::min(kCheckEvery, n - done);
      {
        py::gil_scoped_release release;
        for (int64_t i = 0; i < chunk && !world_->Done(); ++i) {
          status = world_->Step();
          ++done;
          if (!status.ok()) break;
        }
      }
      if (!status.ok()) throw std::runtime_error("scoopsim: step failed: " + status.message);
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
    return done;
  }

  py::array_t<double> ScoopWrench(const std::string& frame) const {
    const sim::ScoopWrench* w = world_->scoop_wrench();
    if (w == nullptr) throw std::runtime_error("scoop_wrench: the scene has no dig");
    if (frame == "world") return Six(w->force_world, w->torque_world);
    if (frame == "l_scoop") return Six(w->force_scoop, w->torque_scoop);
    if (frame == "body") return Six(w->force_body, w->torque_body);
    throw py::value_error("scoop_wrench: frame: expected world, body or l_scoop, got " + frame);
  }

  // The scoop's pose for the coming steps: position [m], quaternion w x y z (normalised here),
  // and its twist (world frame) [m/s], [rad/s].
  void SetScoopPose(const std::array<double, 3>& position, const std::array<double, 4>& quaternion,
                    const std::array<double, 3>& velocity,
                    const std::array<double, 3>& angular_velocity) {
    if (external_ == nullptr)
      throw std::runtime_error(
          "set_scoop_pose: the World was made with driver='scene'; "
          "make it with World(scene, driver='python')");
    external_->SetMotion(MotionOf(position, quaternion, velocity, angular_velocity));
  }
  static dem::MeshMotion MotionOf(const std::array<double, 3>& position,
                                  const std::array<double, 4>& quaternion,
                                  const std::array<double, 3>& velocity,
                                  const std::array<double, 3>& angular_velocity) {
    const double n = std::sqrt(quaternion[0] * quaternion[0] + quaternion[1] * quaternion[1] +
                               quaternion[2] * quaternion[2] + quaternion[3] * quaternion[3]);
    if (!(n > 0)) throw py::value_error("scoop pose: quaternion: expected a non-zero w x y z");
    dem::MeshMotion m;
    m.pose.position = {position[0], position[1], position[2]};
    m.pose.orientation = {quaternion[0] / n, quaternion[1] / n, quaternion[2] / n,
                          quaternion[3] / n};
    m.velocity = {velocity[0], velocity[1], velocity[2]};
    m.angular_velocity = {angular_velocity[0], angular_velocity[1], angular_velocity[2]};
    return m;
  }
  // A (position, quaternion, velocity, angular_velocity) tuple, as scoop_motion() gives.
  static dem::MeshMotion Motion(const py::object& t) {
    return MotionOf(
        t[py::int_(0)].cast<std::array<double, 3>>(), t[py::int_(1)].cast<std::array<double, 4>>(),
        t[py::int_(2)].cast<std::array<double, 3>>(), t[py::int_(3)].cast<std::array<double, 3>>());
  }
  // The scoop's pose and twist at the end of the last step (its start pose before the first).
  py::tuple ScoopMotion() const {
    const int k = world_->scoop_mesh();
    if (k < 0) throw std::runtime_error("scoop_motion: the scene has no dig");
    const dem::MeshMotion& m = world_->system().mesh_motion(k);
    const dem::Quat& q = m.pose.orientation;
    auto v3 = [](const dem::Vec3& v) { return std::array<double, 3>{v.x, v.y, v.z}; };
    return py::make_tuple(v3(m.pose.position), std::array<double, 4>{q.w, q.x, q.y, q.z},
                          v3(m.velocity), v3(m.angular_velocity));
  }
  void EndPass() {
    if (external_ == nullptr) throw std::runtime_error("end_pass: only with driver='python'");
    external_->EndPass();
  }

  sim::ArmDriver& arm() {
    if (arm_ == nullptr)
      throw std::runtime_error("the scene's scoop is not held by an arm coupled to the DEM (arm:)");
    return *arm_;
  }

  sim::World& world() { return *world_; }

 private:
  std::unique_ptr<sim::World> world_;
  sim::ExternalPoseDriver* external_ = nullptr;  // owned by world_'s dig
  sim::ArmDriver* arm_ = nullptr;                // the same, with an arm scene
};

}  // namespace

PYBIND11_MODULE(_scoopsim, m) {
  m.doc() = "scoopsim's compiled half; use the package scoopsim.";

  // sim::InputError as scoopsim.InputError (a ValueError) with file, line, key, expected, got
  // as attributes; str() is the CLI's one line.
  static py::exception<sim::InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const sim::InputError& e) {
      py::object error = py::handle(input_error.ptr())(e.what());
      error.attr("file") = e.file();
      error.attr("line") = e.line();
      error.attr("key") = e.key();
      error.attr("expected") = e.expected();
      error.attr("got") = e.got();
      PyErr_SetObject(input_error.ptr(), error.ptr());
    }
  });

  py::class_<sim::Scene>(m, "Scene", "A validated scene (sim::LoadScene): read-only.")
      .def_readonly("path", &sim::Scene::path)
      .def_readonly("yaml_text", &sim::Scene::yaml_text)
      .def_readonly("time_step", &sim::Scene::time_step, "[s]")
      .def_readonly("duration", &sim::Scene::duration, "simulated time of a plain run [s]")
      .def_readonly("threads", &sim::Scene::threads)
      .def_readonly("warnings", &sim::Scene::warnings)
      .def_property_readonly("has_dig", [](const sim::Scene& s) { return s.dig.enabled; })
      .def_property_readonly("has_arm", [](const sim::Scene& s) { return s.arm.enabled; })
      .def_property_readonly("passes", [](const sim::Scene& s) { return s.dig.passes; })
      .def_property_readonly("bite_depth", [](const sim::Scene& s) { return s.dig.bite_depth; })
      .def_property_readonly("bed_material", [](const sim::Scene& s) { return s.bed.material; })
      .def("__repr__", [](const sim::Scene& s) { return "<scoopsim.Scene " + s.path + ">"; });

  m.def(
      "load_scene",
      [](const std::string& path, const py::object& overrides) { return Load(path, overrides); },
      py::arg("path"), py::arg("overrides") = py::none(),
      "Loads and validates a scene as `scoopsim run` does (sim::LoadScene, then sim::Preflight: "
      "the bed file, memory, the path against floor and walls, the arm's reach); overrides as "
      "`--set KEY=VALUE` ({key: value} or a list of 'KEY=VALUE'). Raises scoopsim.InputError.");

  py::class_<PyWorld>(m, "World",
                      "The run loop (sim::World) set up as `scoopsim run` sets it up, without an "
                      "output file: the bed loaded or poured, the scene's dig started.")
      .def(py::init<sim::Scene, int, const std::string&, const py::object&, bool>(),
           py::arg("scene"), py::arg("threads") = 0, py::arg("driver") = "scene",
           py::arg("scoop_motion") = py::none(), py::arg("adaptive_threads") = true,
           "threads 0: the scene's `threads` (0 there: all cores), as the CLI. driver 'scene': the "
           "scene's own (path, arm); 'python': the "
           "scoop where set_scoop_pose puts it, starting at scoop_motion (a tuple as "
           "scoop_motion() gives) or level above the bed's middle. adaptive_threads: as the CLI, "
           "fewer workers while they are faster (a busy core); the same results either way.")
      .def("set_scoop_pose", &PyWorld::SetScoopPose, py::arg("position"), py::arg("quaternion"),
           py::arg("velocity") = std::array<double, 3>{0, 0, 0},
           py::arg("angular_velocity") = std::array<double, 3>{0, 0, 0},
           "(driver='python') the scoop's pose for the coming steps: l_scoop's origin [m] and "
           "orientation (w x y z) in the world, its twist [m/s], [rad/s] (world)")
      .def(
          "joint_state",
          [](PyWorld& w) {
            const sim::ArmDriver::JointState s = w.arm().joint_state();
            py::dict d;
            d["q"] = py::array(py::cast(s.q));
            d["qdot"] = py::array(py::cast(s.qd));
            d["tau"] = py::array(py::cast(s.applied));
            d["reference"] = py::array(py::cast(s.reference));
            return d;
          },
          "(arm scene) the last Bullet step's joints: q [rad], qdot [rad/s], tau (the applied, "
          "clamped torque) [N m] and the reference the PID followed [rad]")
      .def(
          "set_joint_reference",
          [](PyWorld& w, const py::object& q) {
            if (q.is_none()) {
              w.arm().ClearJointReference();
              return;
            }
            const std::vector<double> v = q.cast<std::vector<double>>();
            const int n = static_cast<int>(w.arm().report().joints.size());
            if (static_cast<int>(v.size()) != n)
              throw py::value_error("set_joint_reference: expected " + std::to_string(n) +
                                    " joint positions, got " + std::to_string(v.size()));
            w.arm().SetJointReference(v);
          },
          py::arg("q"),
          "(arm scene) the joint PID follows q [rad] from the next Bullet step instead of the "
          "path's IK (None: the path again); fault reactions still take over")
      .def(
          "fault_bits",
          [](PyWorld& w) {
            return py::make_tuple(w.arm().active_faults(), w.arm().latched_faults());
          },
          "(arm scene) (active, latched): arm/fault_monitor.h's ArmFault bits at the last "
          "Bullet step and every flag raised so far")
      .def("scoop_motion", &PyWorld::ScoopMotion,
           "(position [m], quaternion w x y z, velocity [m/s], angular_velocity [rad/s]) of the "
           "scoop at the end of the last step, world frame")
      .def("end_pass", &PyWorld::EndPass,
           "(driver='python') ends the current pass at the next step: the sample is taken out "
           "and the next pass begins (after the last, done() is true)")
      .def("step", &PyWorld::Step, py::arg("n") = 1,
           "Up to n steps (fewer at the run's end); returns the steps done. Releases the GIL; "
           "Ctrl-C raises KeyboardInterrupt between steps.")
      .def_property_readonly(
          "time", [](PyWorld& w) { return w.world().system().time(); },
          "the state's time [s] (t = 0 at the pour's start)")
      .def_property_readonly("time_step", [](PyWorld& w) { return w.world().StepSize(); })
      .def("done", [](PyWorld& w) { return w.world().Done(); })
      .def(
          "state_hash", [](PyWorld& w) { return w.world().system().StateHash(); },
          "dem::System::StateHash(): the root attribute state_hash of `scoopsim run`'s output")
      .def(
          "particles",
          [](py::object self, bool copy) {
            const dem::Particles& p = self.cast<PyWorld&>().world().system().particles();
            py::dict d;
            d["positions"] = View(p.x, 3, self, copy);
            d["velocities"] = View(p.v, 3, self, copy);
            d["radii"] = View(p.radius, 1, self, copy);
            py::array_t<int64_t> ids(static_cast<py::ssize_t>(p.size()));
            std::copy(p.id.begin(), p.id.end(), ids.mutable_data());
            d["ids"] = ids;
            return d;
          },
          py::arg("copy") = false,
          "dict of positions (n,3) [m], velocities (n,3) [m/s], radii (n,) [m] (read-only views "
          "into the World, in storage order, valid until the next step; copy=True for copies) "
          "and ids (n,), the persistent ids.")
      .def("scoop_wrench", &PyWorld::ScoopWrench, py::arg("frame") = "world",
           "[Fx Fy Fz Tx Ty Tz] [N, N m] of the last step about the scoop's CoM, in frame "
           "'world', 'body' (the study's) or 'l_scoop'.");

  m.def("fault_names", &sim::FaultNames, py::arg("bits"),
        "the names of the ArmFault bits set in `bits` (World.fault_bits())");

  m.def(
      "_run",
      [](const std::string& path, const std::string& out, const py::object& overrides, int threads,
         bool quiet, double stop_after) {
        sim::Scene scene = Load(path, overrides);
        for (const std::string& w : scene.warnings)
          py::print("scoopsim: warning:", w,
                    py::arg("file") = py::module_::import("sys").attr("stderr"));
        sim::RunOptions options;
        options.threads = threads > 0 ? threads : scene.threads;
        options.output = out;
        options.quiet = quiet;
        options.stop_after = stop_after;
        options.adaptive_threads = true;  // as the CLI's run (the same results either way)
        int status = 0;
        {
          StopHandlers stop;
          {
            py::gil_scoped_release release;
            status = sim::RunScene(scene, options);
          }
          StopHandlers::RaiseIfStopped(status);
        }
        return status;
      },
      py::arg("path"), py::arg("out"), py::arg("overrides") = py::none(), py::arg("threads") = 0,
      py::arg("quiet") = false, py::arg("stop_after") = 0.0);

  py::class_<sim::WrenchTable>(m, "_Table")
      .def(py::init<const std::string&>())
      .def("materials", &sim::WrenchTable::materials)
      .def("bite_depths", &sim::WrenchTable::bite_depths)
      .def("passes", &sim::WrenchTable::passes)
      .def("rho", &sim::WrenchTable::rho)
      .def(
          "query",
          [](const sim::WrenchTable& t, const std::string& material,
             py::array_t<double, py::array::c_style | py::array::forcecast> depth,
             py::array_t<int64_t, py::array::c_style | py::array::forcecast> pass,
             py::array_t<double, py::array::c_style | py::array::forcecast> rho, bool clamp,
             const std::string& frame) {
            if (frame != "l_scoop" && frame != "body")
              throw py::value_error("query: frame: expected l_scoop or body, got " + frame);
            const auto f =
                frame == "body" ? sim::WrenchTable::Frame::kBody : sim::WrenchTable::Frame::kScoop;
            const py::ssize_t n = depth.size();
            if (pass.size() != n || rho.size() != n)
              throw py::value_error("query: expected arrays of one size");
            py::array_t<double> out({n, py::ssize_t{6}});
            double* o = out.mutable_data();
            const double* d = depth.data();
            const int64_t* p = pass.data();
            const double* r = rho.data();
            for (py::ssize_t i = 0; i < n; ++i) {
              const std::array<double, 6> w =
                  t.Query(material, 1e3 * d[i], static_cast<int>(p[i]), 1e3 * r[i], clamp, f);
              std::copy(w.begin(), w.end(), o + 6 * i);
            }
            return out;
          },
          py::arg("material"), py::arg("bite_depth"), py::arg("pass_"), py::arg("rho"),
          py::arg("clamp") = false, py::arg("frame") = "l_scoop");

  py::class_<arm::ArmModel, std::shared_ptr<arm::ArmModel>>(
      m, "Arm", "An arm read from a URDF (arm::LoadArmModel).")
      .def(py::init([](const std::string& urdf) {
             return std::make_shared<arm::ArmModel>(arm::LoadArmModel(urdf));
           }),
           py::arg("urdf"))
      .def_property_readonly("dof", &arm::ArmModel::dof)
      .def(
          "gravity_torques",
          [](const arm::ArmModel& a, const Eigen::VectorXd& q, double g) {
            if (q.size() != a.dof())
              throw py::value_error("gravity_torques: q: expected dof entries");
            return arm::GravityTorques(a, q, Eigen::Vector3d(0, 0, -g));
          },
          py::arg("q"), py::arg("g") = 9.81,
          "the joint torques that hold the arm still at q [rad] under g [m/s^2] along the base's "
          "-z [N m]")
      .def(
          "jacobian",
          [](const arm::ArmModel& a, const Eigen::VectorXd& q) {
            if (q.size() != a.dof()) throw py::value_error("jacobian: q: expected dof entries");
            const Eigen::Vector3d tip = arm::LinkPose(a, q, a.tip_link).translation();
            return Eigen::MatrixXd(arm::PointJacobian(a, q, a.dof(), tip));
          },
          py::arg("q"),
          "the geometric Jacobian (6, dof) of the tip link's origin, base axes: rows 0-2 its "
          "velocity, 3-5 the angular velocity")
      .def(
          "link_pose",
          [](const arm::ArmModel& a, const Eigen::VectorXd& q, const std::string& link) {
            if (q.size() != a.dof()) throw py::value_error("link_pose: q: expected dof entries");
            return Eigen::Matrix4d(arm::LinkPose(a, q, link.empty() ? a.tip_link : link).matrix());
          },
          py::arg("q"), py::arg("link") = "",
          "the 4 x 4 pose of `link` (default: the tip, l_scoop) in the base frame at q")
      .def("info", [](const arm::ArmModel& a) {
        py::dict d;
        d["robot"] = a.robot_name;
        d["source"] = a.source;
        d["base_link"] = a.bodies[0].link;
        d["tip_link"] = a.tip_link;
        py::list joints;
        for (int i = 0; i < a.dof(); ++i) {
          const arm::Joint& j = a.joints[i];
          py::dict jd;
          jd["name"] = j.name;
          jd["type"] = arm::JointTypeName(j.type);
          jd["lower"] = j.has_position_limits ? py::cast(j.lower) : py::none();
          jd["upper"] = j.has_position_limits ? py::cast(j.upper) : py::none();
          jd["effort"] = j.effort;
          jd["velocity"] = j.velocity;
          jd["damping"] = j.damping;
          jd["friction"] = j.friction;
          jd["mass"] = a.bodies[i + 1].inertial.mass;
          joints.append(jd);
        }
        d["joints"] = joints;
        d["moving_mass"] = a.MovingMass();
        d["base_mass"] = a.bodies[0].inertial.mass;
        return d;
      });
}
