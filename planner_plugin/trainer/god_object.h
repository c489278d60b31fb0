// pectus trainer: proxy ("god-object") haptic rendering of the introducer over the scene's triangle meshes
// (Zilles & Salisbury 1995; Ruspini, Kolarov & Khatib 1997). The proxy follows the device's tip but never
// crosses a surface: each tick it moves towards the tip along the surface, held by up to three constraint
// planes, and the force is the spring between them, F = -k x (dissertation Eq. 15), with k the touched
// tissue's stiffness, friction (a static and a dynamic cone), force shading over the vertex normals, and
// a damper that keeps the sampled spring passive. The introducer's shaft (a capsule behind the tip)
// collides too, by penalty. Update() allocates nothing, locks nothing and never throws.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>

#include "planner_plugin/trainer/trainer_scene.h"
#include "shape/core/geometry.h"

namespace pectus::trainer {

/// An introducer (the Lorenz pectus introducer comes in several sizes; the dissertation models three).
struct Introducer {
  const char* name;
  double diameter_mm;      ///< of the shaft (its capsule's radius is half of it)
  double shaft_length_mm;  ///< from the tip to the handle
};
/// The three sizes: small (6 mm, 250 mm), medium (8 mm, 300 mm), large (10 mm, 350 mm). Assumed sizes:
/// the dissertation names three but gives no dimensions (docs/trainer.md).
const std::array<Introducer, 3>& IntroducerSizes();

/// Rendering settings. Stiffness per Organ (N/mm): bone 2.0 (within a Phantom Premium's 3.5), the
/// pericardium 0.4, the lungs 0.15.
struct ProxyOptions {
  std::array<double, kNumOrgans> stiffness_n_per_mm = {2.0, 0.4, 0.15};
  double static_friction = 0.3;   ///< the proxy sticks while the tangential pull is within this of the normal
  double dynamic_friction = 0.2;  ///< and slides keeping this ratio when it is not
  bool force_shading = true;      ///< normal force along the interpolated vertex normal (one plane only)
  /// Damping of the depth's rate (N s/mm). Colgate & Schenkel's bound for a spring sampled at T is
  /// b > k T / 2 (0.001 for bone at 1 kHz); the rate here is a backward difference and the shaft's
  /// penalty adds stiffness, and press-release cycles on the sternum gained energy at k T (0.002):
  /// the default is 2 k T, which measured passive (tests/planner_plugin/trainer/god_object_test.cc).
  double damping_n_s_per_mm = 0.004;
  double max_force_n = 8.5;            ///< the device's limit (the force is scaled down to it)
  double surface_offset_mm = 1e-4;     ///< the proxy rests this far in front of a surface
  double shaft_sample_spacing_mm = 4;  ///< shaft capsule tested at points this far apart
  /// The part of the shaft behind the tip that collides, mm: the introducer's curved distal end, taken
  /// straight along the tool's axis for 20 mm (3 mm off a curve of 60 mm radius); the shaft behind it lies
  /// in the tunnel the tip has made. Default 20.
  double shaft_collision_length_mm = 20;
  bool IsValid(std::string* why) const;
};

/// One tick's outcome.
struct ProxyContact {
  Eigen::Vector3d proxy_mm = Eigen::Vector3d::Zero();    ///< where the tip is drawn
  Eigen::Vector3d goal_mm = Eigen::Vector3d::Zero();     ///< the device's tip
  Eigen::Vector3d force_n = Eigen::Vector3d::Zero();     ///< to the device (tip and shaft)
  Eigen::Vector3d torque_nmm = Eigen::Vector3d::Zero();  ///< of the shaft's forces about the tip
  int num_planes = 0;                                    ///< constraint planes holding the proxy (0-3)
  std::int32_t faces[3] = {-1, -1, -1};                  ///< their faces
  std::uint32_t organs_touched = 0;                      ///< bit Organ: the tip or the shaft touches it
  double pericardium_force_n = 0;                        ///< magnitude of the force the pericardium takes
  bool stuck = false;                                    ///< held by static friction
};

/// The god-object of one introducer in one scene (which must outlive it).
class GodObject {
 public:
  /// Throws Error(kUsage) for invalid options.
  GodObject(const TrainerScene& scene, const Introducer& introducer, const ProxyOptions& options = {});
  /// Puts the proxy at `tip_mm` (free space) and forgets the contacts.
  void Reset(const Eigen::Vector3d& tip_mm);
  /// One servo tick: the device's tip and orientation (axis = orientation * (0, 0, 1), handle to tip),
  /// the period dt_s. A non-finite reading renders no force and leaves the proxy where it was.
  const ProxyContact& Update(const Eigen::Vector3d& tip_mm, const Eigen::Quaterniond& orientation,
                             double dt_s) noexcept;
  const ProxyContact& contact() const { return contact_; }
  const Introducer& introducer() const { return introducer_; }

 private:
  const TrainerScene* scene_;
  Introducer introducer_;
  ProxyOptions options_;
  Points3 vertex_normals_;  // of the collision mesh, for force shading
  ProxyContact contact_;
  double last_depth_mm_ = 0;

  /// Moves from `from` towards `target` along the surfaces (at most three planes); returns where it ends.
  Eigen::Vector3d Slide(const Eigen::Vector3d& from, const Eigen::Vector3d& target,
                        ProxyContact* c) const noexcept;
};

}  // namespace pectus::trainer
