#include "planner_plugin/ribcage/patient_ribcage.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "shape/core/error.h"
#include "shape/core/geometry.h"

namespace pectus::planner {
namespace {

Points3 Scaled(const Points3& p, const Eigen::Vector3d& scale) {
  Points3 out = p;
  for (int c = 0; c < 3; ++c) out.col(c) *= scale(c);
  return out;
}

// Throws Error(kBadInput) naming the patient and the part if the map folds a tetrahedron (measurements
// beyond what the generic ribcage's skinning can take), before the finite elements meet it.
void ThrowIfFolded(const GenericRibcage& generic, const Points3& nodes, const PatientMeasurements& targets) {
  Eigen::Index folded = 0, first = -1;
  for (Eigen::Index t = 0; t < generic.tets.rows(); ++t) {
    auto at = [&](int c) -> Eigen::Vector3d { return nodes.row(generic.tets(t, c)).transpose(); };
    if (!(SignedVolume(at(0), at(1), at(2), at(3)) > 0)) {
      if (folded++ == 0) first = t;
    }
  }
  if (folded == 0) return;
  const int part = generic.tet_parts(first);
  const std::string where =
      part == 0 ? std::string("the sternum")
                : std::string(part > 0 ? "left " : "right ") +
                      (generic.regions(first) == kCartilageRegion ? "costal cartilage " : "rib ") +
                      std::to_string(std::abs(part));
  ThrowBadInput("patient measurements",
                "patient " + targets.patient + ": the ribcage fitted to these measurements folds " +
                    std::to_string(folded) + " tetrahedra (first: " + std::to_string(first) + ", in " +
                    where +
                    "); the depression or torsion is beyond what the generic ribcage's skinning can take");
}

}  // namespace

PatientMeasurements MeasurementsOf(const PatientTableRow& row) {
  PatientMeasurements m;
  m.patient = std::to_string(row.patient);
  CopyCtMeasurements(row, &m);
  m.haller_index = row.haller_index;
  return m;
}

bool PatientMeasurements::IsValid(std::string* why) const {
  auto fail = [&](const std::string& reason) {
    if (why) *why = "patient " + patient + ": " + reason;
    return false;
  };
  auto in = [](double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; };
  if (!in(magnification, 0.2, 5.0)) return fail("magnification must be given, 0.2 to 5 (1 if none)");
  if (!in(TrueWidth(), 100, 500)) return fail("ribcage width must be 100 to 500 mm");
  if (!in(TrueDepth(), 60, 400)) return fail("ribcage depth must be 60 to 400 mm");
  if (!in(TrueDepth(), 0, TrueWidth())) return fail("ribcage depth must not exceed its width");
  if (slice_spacing_mm < 0) return fail("slice spacing must not be negative");
  if (!in(SternalLength(), 40, 400)) return fail("sternal length must be 40 to 400 mm");
  if (!in(TrueDepression(), 0, 60)) return fail("sternal depression must be 0 to 60 mm");
  if (!in(TrueDepression(), 0, 0.5 * TrueDepth()))
    return fail("sternal depression must be under half the depth");
  if (!in(torsion_deg, -45, 45)) return fail("sternal torsion must be -45 to 45 degrees");
  if (haller_index != 0 && !in(haller_index, 1, 50))
    return fail("the Haller index must be 1 to 50 (0: unknown)");
  return true;
}

double PatientMeasurements::SternalLength() const {
  if (slice_spacing_mm > 0) return (last_sternum_slice - first_sternum_slice) * slice_spacing_mm;
  return sternal_length_mm;
}

bool PatientRibcageOptions::IsValid(std::string* why) const {
  if (!skinning.IsValid(why) || !measurement.IsValid(why)) return false;
  if (!(tolerance_mm > 0 && tolerance_mm < 1) || max_iterations < 1) {
    if (why) *why = "tolerance_mm must be in (0, 1) and max_iterations >= 1";
    return false;
  }
  return true;
}

SternumSkinning MakeSternumSkinning(const GenericRibcage& generic, const Eigen::Vector3d& scale,
                                    const SternumSkinningOptions& skinning) {
  Points3 axis(static_cast<Eigen::Index>(generic.sternum_axis.size()), 3);
  std::vector<double> half_width;
  for (std::size_t j = 0; j < generic.sternum_axis.size(); ++j) {
    axis.row(static_cast<Eigen::Index>(j)) =
        generic.nodes.row(generic.sternum_axis[j]).cwiseProduct(scale.transpose());
    half_width.push_back(generic.sternum_half_width[j] * scale.x());
  }
  // The bone's influence rises between the joints of the second and third cartilages.
  return SternumSkinning(std::move(axis), std::move(half_width), generic.rib_attachment_fraction.at(1),
                         generic.rib_attachment_fraction.at(2), scale.x(), skinning);
}

Points3 MapGenericNodes(const GenericRibcage& generic, const PatientMapParameters& parameters,
                        const SternumSkinningOptions& skinning) {
  const SternumSkinning bone = MakeSternumSkinning(generic, parameters.scale, skinning);
  Points3 out = Scaled(generic.nodes, parameters.scale);
  for (Eigen::Index i = 0; i < out.rows(); ++i) {
    out.row(i) =
        bone.Apply(out.row(i).transpose(), parameters.depression_mm, parameters.torsion_rad).transpose();
  }
  return out;
}

PatientRibcage MakePatientRibcage(const GenericRibcage& generic, const PatientMeasurements& targets,
                                  const PatientRibcageOptions& options) {
  std::string why;
  if (!targets.IsValid(&why)) ThrowBadInput("patient measurements", why);
  if (!options.IsValid(&why)) ThrowUsage("patient ribcage options: " + why);
  // The CT is measured on the slice of deepest depression, at the level of the costal margin: without
  // ribs 8-10 that slice has no ribs beside the sternum, and the fit chases a width and depth the
  // ribcage does not have (folding the lower cartilages).
  if (generic.options.rib_pairs < 10) {
    ThrowUsage(
        "patient ribcage: the generic ribcage has " + std::to_string(generic.options.rib_pairs) +
        " rib pairs; fitting CT measurements needs all 10 (the slice of deepest depression crosses the "
        "costal margin, ribs 8-10)");
  }
  PatientRibcage out;
  out.patient = targets.patient;
  out.targets = targets;
  // The bone surface (fixed topology) for the measurements.
  Eigen::VectorXi face_tet;
  out.surface.faces = ExtractLinearBoundary(generic.tets, &face_tet);
  out.surface.face_parts.resize(face_tet.size());
  for (Eigen::Index f = 0; f < face_tet.size(); ++f)
    out.surface.face_parts(f) = generic.tet_parts(face_tet(f));

  const double width = targets.TrueWidth(), depth = targets.TrueDepth(), length = targets.SternalLength();
  const double depression = targets.TrueDepression(), torsion = targets.torsion_deg;
  auto measure = [&](const PatientMapParameters& p) {
    out.surface.nodes = MapGenericNodes(generic, p, options.skinning);
    out.surface.spine_anterior = Scaled(generic.spine_anterior, p.scale);
    return MeasureRibcage(out.surface, options.measurement);
  };
  // Start from the scale of the undeformed generic ribcage, then fixed-point updates: each scale by
  // the ratio of target to measured, the depression by a secant step, the torsion by its residual.
  PatientMapParameters p;
  const RibcageMeasurements generic_size = measure(p);
  p.scale = Eigen::Vector3d(width / generic_size.width_mm, depth / generic_size.depth_mm,
                            length / generic_size.sternal_length_mm);
  p.depression_mm = depression;
  p.torsion_rad = torsion * kDegree;
  double previous_parameter = 0, previous_measured = 0;
  bool have_previous = false;
  RibcageMeasurements m, best_m;
  PatientMapParameters best = p;
  double best_worst = std::numeric_limits<double>::infinity();
  for (out.iterations = 1; out.iterations <= options.max_iterations; ++out.iterations) {
    m = measure(p);
    const double r_w = width - m.width_mm, r_d = depth - m.depth_mm, r_l = length - m.sternal_length_mm;
    const double r_dep = depression - m.depression_mm, r_t = torsion - m.torsion_deg;
    const double worst =
        std::max({std::abs(r_w), std::abs(r_d), std::abs(r_l), std::abs(r_dep), std::abs(r_t)});
    if (worst < best_worst) {
      best_worst = worst;
      best = p;
      best_m = m;
    }
    if (worst <= options.tolerance_mm) {
      out.converged = true;
      break;
    }
    // Relaxed steps after a while, in case the slice of deepest depression hops between two levels.
    const double relax = out.iterations > 10 ? 0.5 : 1.0;
    p.scale.x() *= std::pow(width / m.width_mm, relax);
    p.scale.y() *= std::pow(depth / m.depth_mm, relax);
    p.scale.z() *= std::pow(length / m.sternal_length_mm, relax);
    double gain = 1.0;
    if (have_previous && std::abs(m.depression_mm - previous_measured) > 1e-6) {
      gain = std::clamp((p.depression_mm - previous_parameter) / (m.depression_mm - previous_measured), 0.5,
                        4.0);
    }
    previous_parameter = p.depression_mm;
    previous_measured = m.depression_mm;
    have_previous = true;
    p.depression_mm = std::clamp(p.depression_mm + relax * gain * r_dep, -20.0, 120.0);
    p.torsion_rad += relax * r_t * kDegree;
  }
  // The best iterate (the last one when converged).
  p = best;
  m = best_m;
  out.residual_mm = best_worst;
  if (!out.converged) out.surface.nodes = MapGenericNodes(generic, p, options.skinning);
  out.surface.spine_anterior = Scaled(generic.spine_anterior, p.scale);
  // The spine's anterior surface, which only the Haller index sees: moved along y until the sternum-to-
  // spine distance gives back the CT's index (a few passes, in case the measured slice moves with it).
  if (targets.haller_index > 0) {
    for (int pass = 0; pass < 5; ++pass) {
      const double shift = m.inner_width_mm / targets.haller_index - m.sternum_to_spine_mm;
      if (std::abs(shift) < 1e-3) break;
      out.surface.spine_anterior.col(1).array() += shift;
      out.spine_shift_mm += shift;
      m = MeasureRibcage(out.surface, options.measurement);
    }
  }
  out.iterations = std::min(out.iterations, options.max_iterations);
  out.parameters = p;
  out.measured = m;
  char line[500];
  std::snprintf(line, sizeof(line),
                "patient %s: %s after %d iterations; residuals width %.3f, depth %.3f, sternal length %.3f, "
                "depression %.3f mm, torsion %.3f deg",
                targets.patient.c_str(), out.converged ? "fitted" : "NOT fitted", out.iterations,
                width - m.width_mm, depth - m.depth_mm, length - m.sternal_length_mm,
                depression - m.depression_mm, torsion - m.torsion_deg);
  out.message = line;
  if (targets.haller_index > 0) {
    std::snprintf(line, sizeof(line), "; Haller index %.3f (CT %.3f), the spine moved %+.1f mm",
                  m.haller_index, targets.haller_index, out.spine_shift_mm);
    out.message += line;
  }

  ThrowIfFolded(generic, out.surface.nodes, targets);

  // The quadratic mesh on the fitted corner nodes (mid-edge nodes at the midpoints: straight edges).
  out.mesh = MakeQuadratic(out.surface.nodes, generic.tets, generic.regions);
  out.num_corner_nodes = generic.nodes.rows();
  out.tet_parts = generic.tet_parts;
  std::vector<char> fixed(static_cast<std::size_t>(out.mesh.num_nodes()), 0);
  for (std::int32_t n : generic.fixed_nodes) fixed[n] = 1;
  for (Eigen::Index t = 0; t < out.mesh.num_tets(); ++t) {
    for (int e = 0; e < 6; ++e) {
      if (fixed[out.mesh.tets(t, kTet10Edges[e][0])] == 1 &&
          fixed[out.mesh.tets(t, kTet10Edges[e][1])] == 1) {
        fixed[out.mesh.tets(t, 4 + e)] = 2;
      }
    }
  }
  for (std::size_t i = 0; i < fixed.size(); ++i) {
    if (fixed[i] != 0) out.fixed_nodes.push_back(static_cast<std::int32_t>(i));
  }
  // Bar contact candidates: boundary faces on the sternum's posterior surface.
  const MeshBoundary boundary = ExtractBoundary(out.mesh);
  std::vector<char> posterior(static_cast<std::size_t>(out.mesh.num_nodes()), 0);
  for (std::int32_t n : generic.sternum_posterior_nodes) posterior[n] = 1;
  std::vector<Eigen::Index> contact;
  for (Eigen::Index f = 0; f < boundary.faces.rows(); ++f) {
    if (generic.tet_parts(boundary.face_tet(f)) != 0) continue;
    if (posterior[boundary.faces(f, 0)] && posterior[boundary.faces(f, 1)] &&
        posterior[boundary.faces(f, 2)]) {
      contact.push_back(f);
    }
  }
  out.sternum_posterior_faces.resize(static_cast<Eigen::Index>(contact.size()), 6);
  for (std::size_t k = 0; k < contact.size(); ++k) {
    out.sternum_posterior_faces.row(static_cast<Eigen::Index>(k)) = boundary.faces.row(contact[k]);
  }
  out.sternum_anterior_midline = generic.sternum_anterior_midline;
  auto landmark = [&](const std::string& label, std::int32_t node, const std::string& description) {
    out.landmarks.items.push_back({label, out.mesh.nodes.row(node).transpose(), description});
  };
  // Labels as everywhere in pectus (datasets/chest_landmarks.h): "xiphoid" is the xiphisternal joint.
  landmark("sternal_notch", generic.landmarks.sternal_notch, "suprasternal notch, top of the manubrium");
  const Eigen::Vector3d notch = out.mesh.nodes.row(generic.landmarks.sternal_notch).transpose();
  const Eigen::Vector3d angle = out.mesh.nodes.row(generic.landmarks.manubriosternal_junction).transpose();
  out.landmarks.items.push_back(
      {"manubrium_centre", 0.5 * (notch + angle), "centre of the manubrium, anterior"});
  landmark("sternal_angle", generic.landmarks.manubriosternal_junction,
           "manubriosternal joint, anterior midline");
  landmark("xiphoid", generic.landmarks.xiphisternal_junction, "xiphisternal joint, anterior midline");
  landmark("xiphoid_tip", generic.landmarks.xiphoid_tip, "lower end of the xiphoid process");
  return out;
}

}  // namespace pectus::planner
