// pectus datasets: pictures of synthetic subjects — the true skin, the sweeps coloured by sweep, a
// depression's depth map — for previews (`pectus synth --preview`) and docs/datasets.md. Needs
// pectus::render.
#pragma once

#include <filesystem>

#include "datasets/scan_writer.h"
#include "datasets/synth.h"
#include "shape/render/image.h"
#include "shape/render/mesh_render.h"

namespace pectus::datasets {

/// A view of a subject as View::Front, View::Oblique(yaw_deg, pitch_deg) would show its chest frame, turned
/// by the subject's pose so that the chest is seen the same way whatever its pose in the scan frame.
render::View SubjectView(const SyntheticSubject& subject, double yaw_deg, double pitch_deg, int width,
                         int height);

/// The true skin, shaded; with `depth_colours`, coloured by the inward displacement of the chest wall from
/// the same chest without its depression (viridis, 0 to the depression's depth).
render::Image RenderSkin(const SyntheticSubject& subject, const render::View& view,
                         bool depth_colours = false);

/// The sweeps as points, one colour per sweep (render::CategoryColor); `true_poses` maps each sweep by its
/// true pose first (otherwise: as the tracker placed them).
render::Image RenderSweeps(const Scan& scan, const render::View& view, bool true_poses);

/// The skin and the sweeps side by side with titles, written as PNG through `stage`.
void WriteSubjectPreview(const ScannedSubject& subject, const std::filesystem::path& path,
                         const StagePath& stage = {});

}  // namespace pectus::datasets
