#include "planner_plugin/ribcage/build_generic_ribcage.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "planner_plugin/fem/hex_block.h"
#include "planner_plugin/ribcage/internal/ribcage_anatomy.h"
#include "planner_plugin/ribcage/internal/sweep.h"
#include "shape/core/error.h"

namespace pectus::planner {
namespace {

constexpr double kPi = std::numbers::pi;

double Smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// Grid of positions of one block, (n + 1) x (nu + 1) x (nv + 1) as SweepPositions lays it out.
struct Grid {
  int stations = 0, nu = 0, nv = 0;
  std::vector<Eigen::Vector3d> p;
  const Eigen::Vector3d& at(int s, int u, int v) const {
    return p[(static_cast<std::size_t>(s) * (nu + 1) + u) * (nv + 1) + v];
  }
};

// A left rib: positions, where its cartilage starts, and its end window (which block it joins).
struct RibSweep {
  Grid grid;
  int junction_station = 0;  // first cartilage cell
  int window_first = 0;      // first station (sternum or rib above) of the joint
};

class Builder {
 public:
  explicit Builder(const GenericRibcageOptions& o)
      : o_(o), shell_(MakeShell(o.sternum_tilt_deg * kPi / 180)) {
    const double tilt = o.sternum_tilt_deg * kPi / 180;
    arc_ = o.sternal_length_mm / std::cos(tilt);
    tangent_ = Eigen::Vector3d(0, -std::sin(tilt), -std::cos(tilt));
    anterior_ = Eigen::Vector3d(0, -std::cos(tilt), std::sin(tilt));
  }

  GenericRibcage Build() {
    BuildSternum();
    std::vector<RibSweep> left;
    for (int k = 1; k <= o_.rib_pairs; ++k) left.push_back(SweepRib(k, left));
    // Left ribs, then the right ribs as their mirror images.
    std::vector<HexBlock> left_blocks, right_blocks;
    for (int side = 0; side < 2; ++side) {
      auto& blocks = side == 0 ? left_blocks : right_blocks;
      for (int k = 1; k <= o_.rib_pairs; ++k) blocks.push_back(InstantiateRib(k, left[k - 1], side, blocks));
    }
    GenericRibcage out;
    out.options = o_;
    out.shell = shell_;
    out.sternal_arc_length_mm = arc_;
    out.nodes.resize(static_cast<Eigen::Index>(nodes_.size()), 3);
    for (std::size_t i = 0; i < nodes_.size(); ++i)
      out.nodes.row(static_cast<Eigen::Index>(i)) = nodes_[i].transpose();
    std::vector<Eigen::Vector4i> tets;
    std::vector<int> regions, parts;
    auto add = [&](const HexBlock& block, int part, const std::string& name) {
      const std::size_t before = tets.size();
      const int folded = AppendBlockTetrahedra(block, out.nodes, &tets, &regions);
      if (folded > 0)
        ThrowFailure("generic ribcage: " + std::to_string(folded) + " folded tetrahedra in " + name);
      parts.insert(parts.end(), tets.size() - before, part);
    };
    add(sternum_, 0, "the sternum");
    for (int k = 1; k <= o_.rib_pairs; ++k) {
      add(left_blocks[k - 1], k, "left rib " + std::to_string(k));
      add(right_blocks[k - 1], -k, "right rib " + std::to_string(k));
      for (const HexBlock* b : {&left_blocks[k - 1], &right_blocks[k - 1]}) {
        for (int u = 0; u <= b->nu; ++u) {
          for (int v = 0; v <= b->nv; ++v) out.fixed_nodes.push_back(b->node(0, u, v));
        }
      }
    }
    out.tets = ToConnectivity(tets);
    out.regions =
        Eigen::Map<const Eigen::VectorXi>(regions.data(), static_cast<Eigen::Index>(regions.size()));
    out.tet_parts = Eigen::Map<const Eigen::VectorXi>(parts.data(), static_cast<Eigen::Index>(parts.size()));
    std::sort(out.fixed_nodes.begin(), out.fixed_nodes.end());
    const int ns = sternum_.ns, mid_u = sternum_.nu / 2, nv = sternum_.nv;
    for (int j = 0; j <= ns; ++j) {
      for (int u = 0; u <= sternum_.nu; ++u) out.sternum_posterior_nodes.push_back(sternum_.node(j, u, 0));
      out.sternum_anterior_midline.push_back(sternum_.node(j, mid_u, nv));
      out.sternum_axis.push_back(sternum_.node(j, mid_u, nv / 2));
      out.sternum_half_width.push_back(0.5 * SternumWidth()(static_cast<double>(j) / ns));
    }
    std::sort(out.sternum_posterior_nodes.begin(), out.sternum_posterior_nodes.end());
    out.landmarks.sternal_notch = sternum_.node(0, mid_u, nv);
    out.landmarks.manubriosternal_junction =
        sternum_.node(static_cast<int>(std::lround(kManubriumEnd * ns)), mid_u, nv);
    out.landmarks.xiphisternal_junction =
        sternum_.node(static_cast<int>(std::lround(kBodyEnd * ns)), mid_u, nv);
    out.landmarks.xiphoid_tip = sternum_.node(ns, mid_u, nv);
    for (int k = 0; k < std::min(o_.rib_pairs, 7); ++k) out.rib_attachment_fraction.push_back(attachment_[k]);
    // The spine: the anterior surface of the vertebral bodies, ahead of the rib heads, from above the
    // first rib to well below the ribcage.
    const int samples = 60;
    out.spine_anterior.resize(samples + 1, 3);
    const double top = kRibs[0].head_z + 20, bottom = -2.0 * o_.sternal_length_mm;
    for (int i = 0; i <= samples; ++i) {
      const double z = top + (bottom - top) * i / samples;
      const Eigen::Vector3d head = shell_.Point(shell_.PosteriorPhiAtX(kRibHeadX, z), z);
      out.spine_anterior.row(i) << 0.0, head.y() - o_.vertebral_body_offset_mm, z;
    }
    return out;
  }

 private:
  std::int32_t NewNode(const Eigen::Vector3d& p) {
    nodes_.push_back(p);
    return static_cast<std::int32_t>(nodes_.size() - 1);
  }

  // The sternum: sections along its arc, u from the patient's left edge to the right, v from the
  // posterior surface to the anterior one.
  void BuildSternum() {
    const int ns = o_.sternum_cells_along, nu = o_.sternum_cells_across, nv = o_.sternum_cells_through;
    sternum_.Resize(ns, nu, nv, kSternumRegion);
    for (int j = 0; j <= ns; ++j) {
      const double f = static_cast<double>(j) / ns;
      const Eigen::Vector3d front = f * arc_ * tangent_;
      const double w = SternumWidth()(f), t = SternumThickness()(f);
      for (int u = 0; u <= nu; ++u) {
        for (int v = 0; v <= nv; ++v) {
          const Eigen::Vector3d p = front + (0.5 * w - u * w / nu) * Eigen::Vector3d::UnitX() +
                                    (static_cast<double>(v) / nv - 1.0) * t * anterior_;
          sternum_.node(j, u, v) = NewNode(p);
        }
      }
    }
  }

  // Window of the sternum's left face (u = 0) for rib k: (nu_rib + 1) x (nv + 1) node ids.
  int SternumWindowFirst(int k) {
    const int first = static_cast<int>(
        std::lround(kRibs[k - 1].sternal_fraction * o_.sternum_cells_along - 0.5 * o_.rib_cells_height));
    if (static_cast<int>(attachment_.size()) < k) {
      attachment_.push_back((first + 0.5 * o_.rib_cells_height) / o_.sternum_cells_along);
    }
    return first;
  }

  Eigen::Vector3d ShellFrameOut(const Eigen::Vector3d& p, const Eigen::Vector3d& tangent) const {
    Eigen::Vector3d n = shell_.Normal(shell_.PhiOf(p), p.z());
    return (n - n.dot(tangent) * tangent).normalized();
  }

  RibSweep SweepRib(int k, const std::vector<RibSweep>& previous) {
    const RibAnatomy& r = kRibs[k - 1];
    const int nu = o_.rib_cells_height, nv = o_.rib_cells_thickness;
    if (nv != o_.sternum_cells_through)
      ThrowUsage("generic ribcage: rib_cells_thickness must equal sternum_cells_through");
    RibSweep out;
    // The joint: a window on the sternum's left face (ribs 1-7) or on the lower border of the cartilage
    // above.
    std::vector<Eigen::Vector3d> window;
    if (k <= 7) {
      out.window_first = SternumWindowFirst(k);
      if (out.window_first < 1 || out.window_first + nu > o_.sternum_cells_along - 1) {
        ThrowUsage("generic ribcage: rib " + std::to_string(k) + "'s sternal joint falls off the sternum");
      }
      if (k > 1 && out.window_first <= previous[k - 2].window_first + nu) {
        ThrowUsage("generic ribcage: the sternal joints of ribs " + std::to_string(k - 1) + " and " +
                   std::to_string(k) + " touch; use more sternum_cells_along");
      }
      for (int iu = 0; iu <= nu; ++iu) {
        for (int iv = 0; iv <= nv; ++iv)
          window.push_back(nodes_[sternum_.node(out.window_first + iu, 0, iv)]);
      }
    } else {
      const RibSweep& above = previous[k - 2];
      const int cartilage_cells = above.grid.stations - 1 - above.junction_station;
      out.window_first =
          above.junction_station + static_cast<int>(std::lround(kMarginFraction * cartilage_cells)) - nu / 2;
      if (out.window_first < above.junction_station || out.window_first + nu > above.grid.stations - 2) {
        ThrowUsage("generic ribcage: the cartilage of rib " + std::to_string(k - 1) +
                   " is too short for rib " + std::to_string(k) + " to join it");
      }
      for (int iu = 0; iu <= nu; ++iu) {
        for (int iv = 0; iv <= nv; ++iv)
          window.push_back(above.grid.at(out.window_first + iu, above.grid.nu, iv));
      }
    }
    Eigen::Vector3d window_centre = Eigen::Vector3d::Zero();
    for (const auto& p : window) window_centre += p / static_cast<double>(window.size());
    const Eigen::Vector3d window_u =
        (window[static_cast<std::size_t>(nu) * (nv + 1) + nv / 2] - window[nv / 2]).normalized();
    Eigen::Vector3d window_v = window[static_cast<std::size_t>(nu / 2) * (nv + 1) + nv] -
                               window[static_cast<std::size_t>(nu / 2) * (nv + 1)];
    window_v = (window_v - window_v.dot(window_u) * window_u).normalized();
    const Eigen::Vector3d end_tangent =
        window_u.cross(window_v);  // into the joint, for a left rib (up = out x tangent)

    // Rib: from the head around the shell to the costochondral junction, descending smoothly.
    const double phi_head = shell_.PosteriorPhiAtX(kRibHeadX, r.head_z);
    const double phi_junction = shell_.AnteriorPhiAtX(r.junction_x, r.junction_z);
    std::vector<Eigen::Vector3d> rib_line;
    const int dense = 400;
    for (int i = 0; i <= dense; ++i) {
      const double t = static_cast<double>(i) / dense;
      const double phi = phi_head + t * (phi_junction - phi_head);
      rib_line.push_back(shell_.Point(phi, r.head_z + (r.junction_z - r.head_z) * Smoothstep(t)));
    }
    const Eigen::Vector3d junction = rib_line.back();
    const Eigen::Vector3d junction_tangent = (rib_line[dense] - rib_line[dense - 4]).normalized();
    // Cartilage: a Hermite curve laid onto the shell. It arrives at the joint between the face's normal
    // and its own heading, and its last sections turn parallel to the joint face (sheared cells rather
    // than a kink).
    const double window_height =
        (window[static_cast<std::size_t>(nu) * (nv + 1) + nv / 2] - window[nv / 2]).norm();
    const double window_thickness = (window[static_cast<std::size_t>(nu / 2) * (nv + 1) + nv] -
                                     window[static_cast<std::size_t>(nu / 2) * (nv + 1)])
                                        .norm();
    const double joint_length = 1.5 * std::max(window_height, window_thickness);
    const double chord = (window_centre - junction).norm();
    // A false rib's cartilage turns up into the border of the one above; a true rib's arrives obliquely.
    const Eigen::Vector3d arrival =
        k > 7 ? end_tangent
              : Eigen::Vector3d((end_tangent + (window_centre - junction).normalized()).normalized());
    const double start_weight = k > 7 ? 0.4 : 0.8, end_weight = k > 7 ? 1.4 : 0.8;
    std::vector<Eigen::Vector3d> cartilage_line = HermiteCurve(
        junction, start_weight * chord * junction_tangent, window_centre, end_weight * chord * arrival, 200);
    for (std::size_t i = 1; i + 1 < cartilage_line.size(); ++i) {
      const Eigen::Vector3d& p = cartilage_line[i];
      cartilage_line[i] = shell_.Point(shell_.PhiOf(p), p.z());
    }
    const int rib_cells =
        std::max(4, static_cast<int>(std::lround(PolylineLength(rib_line) / o_.rib_cell_length_mm)));
    // Cartilage cells are 4 mm to the cartilage's height over rib_cells_height (6 mm) long, whatever the
    // ribs' cells. Longer ones
    // make a false rib's joint (rib_cells_height cells of the cartilage above) taller than the cartilage
    // that arrives there, and ribs 9 and 10 folded from 10 mm cells on; shorter ones make the last cell
    // before a sternal joint thinner than the sternum's face is uneven, and rib 1 folded below 2.7 mm.
    const double cartilage_cell_mm = std::clamp(o_.rib_cell_length_mm, 4.0, kCartilageHeight / nu);
    const int cartilage_cells =
        std::max(4, static_cast<int>(std::lround(PolylineLength(cartilage_line) / cartilage_cell_mm)));
    std::vector<Eigen::Vector3d> centres = ResampleByArcLength(rib_line, rib_cells);
    const std::vector<Eigen::Vector3d> cartilage = ResampleByArcLength(cartilage_line, cartilage_cells);
    centres.insert(centres.end(), cartilage.begin() + 1, cartilage.end());
    out.junction_station = rib_cells;

    // Sections: the rib lies flat in the shell (thickness along the shell normal); near the joint the
    // section turns into the joint face's frame and size.
    const int n = static_cast<int>(centres.size());
    std::vector<double> to_end(static_cast<std::size_t>(n), 0.0);
    for (int s = n - 2; s >= 0; --s) to_end[s] = to_end[s + 1] + (centres[s + 1] - centres[s]).norm();
    std::vector<SweepStation> stations(static_cast<std::size_t>(n));
    for (int s = 0; s < n; ++s) {
      const Eigen::Vector3d tangent =
          s == n - 1 ? end_tangent
                     : (centres[std::min(s + 1, n - 1)] - centres[std::max(s - 1, 0)]).normalized();
      SweepStation& st = stations[s];
      st.centre = centres[s];
      Eigen::Vector3d out_dir = ShellFrameOut(centres[s], tangent);
      if (s <= rib_cells) {
        const double t = static_cast<double>(s) / rib_cells;  // head: rounder and smaller
        const double shaft = Smoothstep(t / 0.2);
        st.height = 10.0 + (r.shaft_height - 10.0) * shaft;
        st.thickness = 8.0 + (r.shaft_thickness - 8.0) * shaft;
      } else {
        const double t = static_cast<double>(s - rib_cells) / cartilage_cells;
        const double blend = Smoothstep(t / 0.3);
        st.height = r.shaft_height + (kCartilageHeight - r.shaft_height) * blend;
        st.thickness = r.shaft_thickness + (kCartilageThickness - r.shaft_thickness) * blend;
      }
      const double joint = s < rib_cells ? 0.0 : 1.0 - Smoothstep(to_end[s] / joint_length);
      Eigen::Vector3d up_dir = out_dir.cross(tangent).normalized();
      up_dir = ((1 - joint) * up_dir + joint * window_u).normalized();
      out_dir = ((1 - joint) * out_dir + joint * window_v);
      st.up = up_dir;
      st.out = (out_dir - out_dir.dot(up_dir) * up_dir).normalized();
      st.height += joint * (window_height - st.height);
      st.thickness += joint * (window_thickness - st.thickness);
    }
    out.grid.stations = n;
    out.grid.nu = nu;
    out.grid.nv = nv;
    out.grid.p = SweepPositions(stations, nu, nv, &window, std::min(3, cartilage_cells - 1));
    return out;
  }

  // Node ids and block of rib k on one side (0 left, 1 right = mirror image).
  HexBlock InstantiateRib(int k, const RibSweep& sweep, int side, const std::vector<HexBlock>& same_side) {
    const int n = sweep.grid.stations, nu = sweep.grid.nu, nv = sweep.grid.nv;
    HexBlock block;
    block.Resize(n - 1, nu, nv, kRibRegion);
    for (int s = 0; s < n - 1; ++s) {
      for (int u = 0; u <= nu; ++u) {
        for (int v = 0; v <= nv; ++v) {
          Eigen::Vector3d p = sweep.grid.at(s, u, v);
          if (side == 1) p.x() = -p.x();
          block.node(s, u, v) = NewNode(p);
        }
      }
    }
    for (int u = 0; u <= nu; ++u) {
      for (int v = 0; v <= nv; ++v) {
        if (k <= 7) {
          block.node(n - 1, u, v) = sternum_.node(sweep.window_first + u, side == 0 ? 0 : sternum_.nu, v);
        } else {
          const HexBlock& above = same_side[k - 2];
          block.node(n - 1, u, v) = above.node(sweep.window_first + u, above.nu, v);
        }
      }
    }
    for (int s = sweep.junction_station; s < n - 1; ++s) {
      for (int u = 0; u < nu; ++u) {
        for (int v = 0; v < nv; ++v) block.cell_region(s, u, v) = kCartilageRegion;
      }
    }
    return block;
  }

  const GenericRibcageOptions& o_;
  ChestShell shell_;
  double arc_ = 0;
  Eigen::Vector3d tangent_, anterior_;
  std::vector<Eigen::Vector3d> nodes_;
  HexBlock sternum_;
  std::vector<double> attachment_;
};

}  // namespace

bool GenericRibcageOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& reason) {
    if (why != nullptr) *why = reason;
    return false;
  };
  if (rib_pairs < 7 || rib_pairs > 10) return fail("rib_pairs must be 7 to 10");
  if (!(sternum_tilt_deg >= 0 && sternum_tilt_deg <= 45)) return fail("sternum_tilt_deg must be 0 to 45");
  if (!(sternal_length_mm > 50 && sternal_length_mm < 400))
    return fail("sternal_length_mm must be 50 to 400");
  if (sternum_cells_along < 16 || sternum_cells_across < 2 || sternum_cells_across % 2 != 0 ||
      sternum_cells_through < 2 || sternum_cells_through % 2 != 0) {
    return fail("sternum cells: along >= 16, across and through even and >= 2");
  }
  if (rib_cells_height < 1 || rib_cells_thickness != sternum_cells_through) {
    return fail("rib_cells_height >= 1 and rib_cells_thickness == sternum_cells_through");
  }
  if (!(rib_cell_length_mm >= 1 && rib_cell_length_mm <= 40))
    return fail("rib_cell_length_mm must be 1 to 40");
  if (!(vertebral_body_offset_mm >= 0 && vertebral_body_offset_mm <= 100)) {
    return fail("vertebral_body_offset_mm must be 0 to 100");
  }
  return true;
}

GenericRibcage BuildGenericRibcage(const GenericRibcageOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("generic ribcage options: " + why);
  Builder builder(options);
  return builder.Build();
}

}  // namespace pectus::planner
