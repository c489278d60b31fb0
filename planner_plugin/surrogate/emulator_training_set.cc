#include "planner_plugin/surrogate/emulator_training_set.h"

#include <cmath>
#include <cstring>
#include <fstream>

#include "planner_plugin/fem/tet_mesh.h"
#include "planner_plugin/ribcage/build_skin_surface.h"
#include "planner_plugin/ribcage/ribcage_fem.h"
#include "planner_plugin/surrogate/emulator_patient_ties.h"
#include "shape/core/error.h"

namespace pectus::planner {

const std::vector<std::string> kCtInputNames = {"width_mm",      "depth_mm",    "sternal_length_mm",
                                                "depression_mm", "torsion_deg", "ct_haller_index"};
const std::vector<std::string> kModelInputNames = {
    "scale_x",         "scale_y",        "scale_z",        "map_depression_mm",
    "map_torsion_deg", "spine_shift_mm", "inner_width_mm", "sternum_to_spine_mm"};

bool EmulatorTrainingSetOptions::IsValid(std::string* why) const {
  if (positions.empty()) {
    if (why) *why = "the training set needs at least one bar position";
    return false;
  }
  for (double s : positions) {
    if (!(s > 0.0 && s < 1.0)) {
      if (why) *why = "bar positions are fractions of the sternal length in (0, 1), got " + std::to_string(s);
      return false;
    }
  }
  std::string reason;
  if (!settings.generic.IsValid(&reason) || !settings.fem.IsValid(&reason) ||
      !settings.skin.IsValid(&reason) || !settings.patient.IsValid(&reason)) {
    if (why) *why = "planner settings: " + reason;
    return false;
  }
  return true;
}

void EmulatorTrainingSet::CheckShapes(const std::string& what) const {
  const Eigen::Index n = num_patients(), q = num_positions(), m = 3 * num_skin_vertices();
  auto fail = [&](const std::string& message) { ThrowBadInput(what, "emulator training set: " + message); };
  if (ct_inputs.rows() != n || ct_inputs.cols() != static_cast<Eigen::Index>(kCtInputNames.size()))
    fail("ct_inputs is not #patients by 6");
  if (model_inputs.rows() != n || model_inputs.cols() != static_cast<Eigen::Index>(kModelInputNames.size()))
    fail("model_inputs is not #patients by 8");
  if (lift_per_newton.rows() != n || lift_per_newton.cols() != q) fail("lift_per_newton is not n by q");
  if (static_cast<Eigen::Index>(skin.size()) != q) fail("not one skin response per position");
  for (const Eigen::MatrixXd& s : skin)
    if (s.rows() != n || s.cols() != m) fail("a skin response is not n by 3 #skin vertices");
  if (!bone.empty() && static_cast<Eigen::Index>(bone.size()) != q)
    fail("not one bone response per position");
  for (const Eigen::MatrixXd& b : bone)
    if (b.rows() != n || b.cols() != bone.front().cols() || b.cols() % 3 != 0)
      fail("the bone responses are not n by 3 #bone vertices alike");
  if (skin_anchor_generic_mm.rows() != n || skin_anchor_generic_mm.cols() != m)
    fail("skin_anchor_generic_mm is not n by 3 #skin vertices");
  const auto nbn = static_cast<Eigen::Index>(boundary_nodes.size());
  if (nbn > 0) {
    if (static_cast<Eigen::Index>(boundary.size()) != q) fail("not one boundary response per position");
    for (const Eigen::MatrixXd& b : boundary)
      if (b.rows() != n || b.cols() != 3 * nbn) fail("a boundary response is not n by 3 #boundary nodes");
    if (static_cast<Eigen::Index>(skin_ties.size()) != n) fail("not one set of skin ties per patient");
    if (static_cast<Eigen::Index>(lift_ties.size()) != n) fail("not one set of lift ties per patient");
    for (const auto& t : lift_ties)
      if (t.rows() != 1 || t.cols() != 3 * nbn) fail("lift ties are not 1 by 3 #boundary nodes");
    for (const auto& t : skin_ties)
      if (t.rows() != num_skin_vertices() || t.cols() != nbn)
        fail("skin ties are not #skin vertices by #boundary nodes");
  } else if (!boundary.empty() || !skin_ties.empty() || !lift_ties.empty()) {
    fail("boundary responses or skin ties without boundary nodes");
  }
}

EmulatorTrainingSet BuildEmulatorTrainingSet(
    const std::vector<PatientTableRow>& rows, const EmulatorTrainingSetOptions& options,
    const std::function<void(std::int64_t, std::int64_t)>& progress) {
  std::string why;
  if (!options.IsValid(&why)) ThrowUsage("emulator training set: " + why);
  const auto n = static_cast<Eigen::Index>(rows.size());
  const auto q = static_cast<Eigen::Index>(options.positions.size());
  EmulatorTrainingSet set;
  set.positions = Eigen::Map<const Eigen::VectorXd>(options.positions.data(), q);
  set.skin_rows = options.settings.skin.rows;
  set.skin_columns = options.settings.skin.columns;
  const Eigen::Index m = 3 * set.num_skin_vertices();
  set.ct_inputs.resize(n, 6);
  set.model_inputs.resize(n, 8);
  set.lift_per_newton.resize(n, q);
  set.skin.assign(static_cast<std::size_t>(q), Eigen::MatrixXd(n, m));
  set.skin_anchor_generic_mm.resize(n, m);
  const GenericRibcage generic = BuildGenericRibcage(options.settings.generic);
  // The generic ribcage's quadratic nodes: the same node order as every patient's mesh.
  const Points3 generic_nodes = MakeQuadratic(generic.nodes, generic.tets, generic.regions).nodes;
  std::vector<BarLoad> loads;
  for (double s : options.positions) loads.push_back({s, false, 1.0});
  for (Eigen::Index i = 0; i < n; ++i) {
    const PatientTableRow& row = rows[static_cast<std::size_t>(i)];
    const PatientMeasurements measurements = MeasurementsOf(row);
    set.patients.push_back(measurements.patient);
    // The patient's ribcage, fitted to its CT measurements (as PlannerSession does).
    PatientRibcage ribcage;
    {
      auto t = set.timings_s.Time("fit");
      ribcage = MakePatientRibcage(generic, measurements, options.settings.patient);
    }
    if (!ribcage.converged && ribcage.residual_mm > 1.0) {
      ThrowFailure("emulator training set: patient " + measurements.patient +
                   ": the generated ribcage does not reproduce the CT measurements: " + ribcage.message);
    }
    set.ct_inputs.row(i) << measurements.TrueWidth(), measurements.TrueDepth(), measurements.SternalLength(),
        measurements.TrueDepression(), measurements.torsion_deg, row.haller_index;
    const PatientMapParameters& p = ribcage.parameters;
    set.model_inputs.row(i) << p.scale.x(), p.scale.y(), p.scale.z(), p.depression_mm,
        p.torsion_rad * 180.0 / 3.14159265358979323846, ribcage.spine_shift_mm,
        ribcage.measured.inner_width_mm, ribcage.measured.sternum_to_spine_mm;
    // The bar at each position with 1 N: displacements per newton.
    std::vector<BarResult> solved;
    {
      auto t = set.timings_s.Time("fem");
      const RibcageFem fem(ribcage, options.settings.fem);
      solved = fem.Solve(loads);
    }
    auto t = set.timings_s.Time("skin");
    const SkinSurface skin = BuildSkinSurface(ribcage, options.settings.skin);
    if (skin.mesh.num_vertices() != set.num_skin_vertices())
      ThrowFailure("emulator training set: patient " + measurements.patient + ": the skin grid has " +
                   std::to_string(skin.mesh.num_vertices()) + " vertices, not rows x columns");
    Points3 anchor = Points3::Zero(skin.mesh.num_vertices(), 3);
    for (std::size_t j = 0; j < skin.ties.size(); ++j) {
      for (const auto& [node, w] : skin.ties[j])
        anchor.row(static_cast<Eigen::Index>(j)) += w * generic_nodes.row(node);
    }
    set.skin_anchor_generic_mm.row(i) = Eigen::Map<const Eigen::RowVectorXd>(anchor.data(), m);
    if (options.boundary_nodes) {
      // The boundary nodes (the same in every patient: one generic topology) and the skin's ties to them.
      const std::vector<std::int32_t> nodes = ExtractBoundary(ribcage.mesh).nodes;
      if (i == 0) {
        set.boundary_nodes = nodes;
        set.boundary.assign(static_cast<std::size_t>(q),
                            Eigen::MatrixXd(n, 3 * static_cast<Eigen::Index>(nodes.size())));
      } else if (nodes != set.boundary_nodes) {
        ThrowFailure("emulator training set: patient " + measurements.patient +
                     ": the mesh's boundary nodes differ from the first patient's");
      }
      EmulatorPatientTies ties = MakeEmulatorPatientTies(ribcage, skin, nodes);
      set.skin_ties.push_back(std::move(ties.skin));
      set.lift_ties.push_back(std::move(ties.lift));
      for (Eigen::Index k = 0; k < q; ++k) {
        const Points3& u = solved[static_cast<std::size_t>(k)].displacement;
        Eigen::MatrixXd& out = set.boundary[static_cast<std::size_t>(k)];
        for (std::size_t b = 0; b < nodes.size(); ++b)
          out.block(i, 3 * static_cast<Eigen::Index>(b), 1, 3) = u.row(nodes[b]);
      }
    }
    BoneSurface bone;
    if (options.bone_surface) bone = MakeBoneSurface(ribcage);
    const auto nb = static_cast<Eigen::Index>(bone.mesh_nodes.size());
    if (options.bone_surface && i == 0)
      set.bone.assign(static_cast<std::size_t>(q), Eigen::MatrixXd(n, 3 * nb));
    for (Eigen::Index k = 0; k < q; ++k) {
      const BarResult& r = solved[static_cast<std::size_t>(k)];
      set.lift_per_newton(i, k) = r.sternum_lift_mm;  // 1 N
      const Points3 u = skin.Deformed(r.displacement) - skin.mesh.vertices.positions;
      set.skin[static_cast<std::size_t>(k)].row(i) = Eigen::Map<const Eigen::RowVectorXd>(u.data(), m);
      if (options.bone_surface) {
        if (set.bone[static_cast<std::size_t>(k)].cols() != 3 * nb)
          ThrowFailure("emulator training set: patient " + measurements.patient +
                       ": the bone surface has another vertex count than the first patient's");
        for (Eigen::Index v = 0; v < nb; ++v)
          set.bone[static_cast<std::size_t>(k)].block(i, 3 * v, 1, 3) =
              r.displacement.row(bone.mesh_nodes[v]);
      }
    }
    if (progress) progress(i + 1, n);
  }
  return set;
}

namespace {

constexpr char kMagic[17] = "pectus-emulator3";

class Writer {
 public:
  explicit Writer(const std::filesystem::path& path) : path_(path), out_(path, std::ios::binary) {
    if (!out_) ThrowFailure("cannot open the file for writing", path.string());
  }
  void Bytes(const void* data, std::size_t size) {
    out_.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out_) ThrowFailure("write failed", path_.string());
  }
  void Int(std::int64_t v) { Bytes(&v, sizeof v); }
  void Doubles(const double* data, Eigen::Index count) {
    Bytes(data, sizeof(double) * static_cast<std::size_t>(count));
    doubles_ += count;
  }
  void RowMajor(const Eigen::MatrixXd& a) {
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r = a;
    Doubles(r.data(), r.size());
  }
  std::int64_t doubles() const { return doubles_; }

 private:
  std::filesystem::path path_;
  std::ofstream out_;
  std::int64_t doubles_ = 0;
};

class Reader {
 public:
  explicit Reader(const std::filesystem::path& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) ThrowBadInput(path.string(), "cannot open the emulator training set");
  }
  void Bytes(void* data, std::size_t size) {
    in_.read(static_cast<char*>(data), static_cast<std::streamsize>(size));
    if (!in_) ThrowBadInput(path_.string(), "the emulator training set is truncated");
  }
  std::int64_t Int(std::int64_t most) {
    std::int64_t v = 0;
    Bytes(&v, sizeof v);
    if (v < 0 || v > most)
      ThrowBadInput(path_.string(),
                    "the emulator training set has a count out of range: " + std::to_string(v));
    return v;
  }
  void Doubles(double* data, Eigen::Index count) {
    Bytes(data, sizeof(double) * static_cast<std::size_t>(count));
    doubles_ += count;
  }
  Eigen::MatrixXd RowMajor(Eigen::Index rows, Eigen::Index cols) {
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> r(rows, cols);
    Doubles(r.data(), r.size());
    return r;
  }
  std::int64_t doubles() const { return doubles_; }
  bool AtEnd() { return in_.peek() == std::char_traits<char>::eof(); }

 private:
  std::filesystem::path path_;
  std::ifstream in_;
  std::int64_t doubles_ = 0;
};

}  // namespace

void SaveEmulatorTrainingSet(const EmulatorTrainingSet& set, const std::filesystem::path& path) {
  set.CheckShapes(path.string());
  Writer w(path);
  w.Bytes(kMagic, 16);
  const Eigen::Index nb = set.bone.empty() ? 0 : set.bone.front().cols() / 3;
  const auto nbn = static_cast<Eigen::Index>(set.boundary_nodes.size());
  for (Eigen::Index v :
       {set.num_patients(), set.num_positions(), set.ct_inputs.cols(), set.model_inputs.cols(),
        static_cast<Eigen::Index>(set.skin_rows), static_cast<Eigen::Index>(set.skin_columns), nb, nbn})
    w.Int(v);
  for (const std::string& id : set.patients) {
    w.Int(static_cast<std::int64_t>(id.size()));
    w.Bytes(id.data(), id.size());
  }
  w.Doubles(set.positions.data(), set.positions.size());
  w.RowMajor(set.ct_inputs);
  w.RowMajor(set.model_inputs);
  w.RowMajor(set.lift_per_newton);
  for (const Eigen::MatrixXd& s : set.skin) w.RowMajor(s);
  for (const Eigen::MatrixXd& b : set.bone) w.RowMajor(b);
  w.RowMajor(set.skin_anchor_generic_mm);
  for (std::int32_t node : set.boundary_nodes) w.Int(node);
  for (const Eigen::MatrixXd& b : set.boundary) w.RowMajor(b);
  for (const auto& ties : set.skin_ties) {
    w.Int(ties.nonZeros());
    for (Eigen::Index r = 0; r < ties.outerSize(); ++r) {
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(ties, r); it; ++it) {
        w.Int(r);
        w.Int(it.col());
        const double value = it.value();
        w.Doubles(&value, 1);
      }
    }
  }
  for (const auto& ties : set.lift_ties) {
    w.Int(ties.nonZeros());
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(ties, 0); it; ++it) {
      w.Int(it.col());
      const double value = it.value();
      w.Doubles(&value, 1);
    }
  }
  w.Int(w.doubles());
}

EmulatorTrainingSet LoadEmulatorTrainingSet(const std::filesystem::path& path) {
  Reader r(path);
  char magic[16];
  r.Bytes(magic, 16);
  if (std::memcmp(magic, kMagic, 16) != 0)
    ThrowBadInput(path.string(),
                  "not an emulator training set of this version (expected the magic 'pectus-emulator3')");
  EmulatorTrainingSet set;
  const Eigen::Index n = r.Int(100000), q = r.Int(1000), pc = r.Int(1000), pm = r.Int(1000);
  set.skin_rows = static_cast<int>(r.Int(100000));
  set.skin_columns = static_cast<int>(r.Int(100000));
  const Eigen::Index nb = r.Int(100000000), nbn = r.Int(100000000);
  for (Eigen::Index i = 0; i < n; ++i) {
    std::string id(static_cast<std::size_t>(r.Int(4096)), '\0');
    r.Bytes(id.data(), id.size());
    set.patients.push_back(id);
  }
  set.positions.resize(q);
  r.Doubles(set.positions.data(), q);
  set.ct_inputs = r.RowMajor(n, pc);
  set.model_inputs = r.RowMajor(n, pm);
  set.lift_per_newton = r.RowMajor(n, q);
  const Eigen::Index m = 3 * set.num_skin_vertices();
  for (Eigen::Index k = 0; k < q; ++k) set.skin.push_back(r.RowMajor(n, m));
  if (nb > 0)
    for (Eigen::Index k = 0; k < q; ++k) set.bone.push_back(r.RowMajor(n, 3 * nb));
  set.skin_anchor_generic_mm = r.RowMajor(n, m);
  for (Eigen::Index b = 0; b < nbn; ++b)
    set.boundary_nodes.push_back(static_cast<std::int32_t>(r.Int(2000000000)));
  for (Eigen::Index k = 0; k < q && nbn > 0; ++k) set.boundary.push_back(r.RowMajor(n, 3 * nbn));
  for (Eigen::Index i = 0; i < n && nbn > 0; ++i) {
    const std::int64_t entries = r.Int(1000000000);
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(static_cast<std::size_t>(entries));
    for (std::int64_t e = 0; e < entries; ++e) {
      const Eigen::Index row = r.Int(set.num_skin_vertices() - 1), col = r.Int(nbn - 1);
      double value = 0.0;
      r.Doubles(&value, 1);
      triplets.emplace_back(static_cast<int>(row), static_cast<int>(col), value);
    }
    Eigen::SparseMatrix<double, Eigen::RowMajor> ties(set.num_skin_vertices(), nbn);
    ties.setFromTriplets(triplets.begin(), triplets.end());
    set.skin_ties.push_back(std::move(ties));
  }
  for (Eigen::Index i = 0; i < n && nbn > 0; ++i) {
    const std::int64_t entries = r.Int(1000000);
    std::vector<Eigen::Triplet<double>> triplets;
    for (std::int64_t e = 0; e < entries; ++e) {
      const Eigen::Index col = r.Int(3 * nbn - 1);
      double value = 0.0;
      r.Doubles(&value, 1);
      triplets.emplace_back(0, static_cast<int>(col), value);
    }
    Eigen::SparseMatrix<double, Eigen::RowMajor> ties(1, 3 * nbn);
    ties.setFromTriplets(triplets.begin(), triplets.end());
    set.lift_ties.push_back(std::move(ties));
  }
  std::int64_t count = 0;
  r.Bytes(&count, sizeof count);
  if (count != r.doubles() || !r.AtEnd())
    ThrowBadInput(path.string(), "the emulator training set's closing count does not match (damaged file)");
  set.CheckShapes(path.string());
  return set;
}

}  // namespace pectus::planner
