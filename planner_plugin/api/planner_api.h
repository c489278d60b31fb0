/* pectus planner plugin: the C interface between a host (`pectus plan`, or any program) and the
 * planner's shared library (libpectus_planner.so). Plain C so that any compiler and language can use
 * it; versioned so that a host never calls a plugin built for another interface.
 *
 * The plugin exports one symbol, pectus_planner_interface(), which returns a table of functions whose
 * first field is the interface version the plugin implements. A host compares it with
 * PECTUS_PLANNER_INTERFACE_VERSION and refuses any other (docs/planner.md, "Plugin interface").
 *
 * Rules every function keeps:
 *  - It never throws and never aborts: every failure comes back as a status code (the same numbers as
 *    pectus's exit codes and pectus::ErrorKind) with a message naming the file, patient or value at fault.
 *  - Units: millimetres, newtons, megapascals, degrees. Frame: LPS (x to the patient's left, y posterior,
 *    z superior) with the origin at the patient's sternal notch on the front of the manubrium.
 *  - Arrays are row-major. Arrays the plugin hands out (PectusPlannerMesh) belong to the planner and stay
 *    valid until it is destroyed; arrays the host passes in are the host's.
 *  - One planner may be used by one thread at a time; different planners are independent. A deformer
 *    (version 2) belongs to one thread; several deformers may read one planner's basis at once, while
 *    nothing else calls that planner.
 *
 * Version 2 added the exact response basis (build_basis) and the real-time deform call: a deformer made
 * once per thread (create_deformer) evaluates the chest for any bar position and force without
 * allocation, lock, exception or I/O, at haptic rates (docs/planner.md, "The exact response basis").
 * Version 3 added the learned emulator's leave-one-patient-out evaluation (evaluate_emulator).
 * Version 4 added the basis as a table for a host that evaluates it itself, such as the planner page in a
 * browser: its modes (basis_modes) and a bar position's coefficients (basis_coefficients).
 * Version 5 added the Nuss trainer (docs/trainer.md): a patient's trainer scene (bones, pericardium, lungs,
 * the planned tunnel), its sessions ticked by the host's haptic device (one tick at a time, or on the
 * plugin's own 1 kHz servo thread), their scores and records, and the thoracoscope's view.
 * Version 6 added the FE dataset one patient at a time, for a task farm (docs/cluster.md): one patient's
 * part file (write_dataset_part), in any order on any process, and the dataset assembled from the parts
 * (assemble_dataset), the same bytes as write_dataset's. Version 7: write_dataset_part's time leaves out
 * the process's one-time generic ribcage, so that a farm can tell it from the patient's work.
 */
#ifndef PECTUS_PLANNER_API_H_
#define PECTUS_PLANNER_API_H_

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The interface version this header describes. Any change to a struct or function below bumps it. */
#define PECTUS_PLANNER_INTERFACE_VERSION 7u
/** The name of the one exported symbol (for dlsym). */
#define PECTUS_PLANNER_ENTRY_POINT "pectus_planner_interface"

/** Status codes: the numbers of pectus::ErrorKind and of the command line's exit codes. */
enum PectusPlannerCode {
  PECTUS_PLANNER_OK = 0,
  PECTUS_PLANNER_FAILURE = 1,  /**< a computation or a write did not succeed */
  PECTUS_PLANNER_USAGE = 2,    /**< the caller asked for something impossible (bad option) */
  PECTUS_PLANNER_BAD_INPUT = 3 /**< a file or value is wrong (malformed table, measurement out of range) */
};

/** What a call did: `code` (PectusPlannerCode) and, unless OK, a message ("FILE:LINE: what is wrong"). */
typedef struct PectusPlannerStatus {
  int32_t code;
  char message[1024];
} PectusPlannerStatus;

/** A patient's CT measurements (dissertation §4.1.1, Figure 24). Lengths in mm on the image; divided
 *  by `magnification` for true size. */
typedef struct PectusPlannerPatient {
  char id[64];                /**< patient identifier, NUL-terminated (e.g. "57") */
  double magnification;       /**< of the CT images; must be given, 1 if none */
  double width_mm;            /**< ribcage width on the slice of deepest depression */
  double depth_mm;            /**< ribcage depth on that slice */
  double sternal_length_mm;   /**< used when slice_spacing_mm is 0 */
  double first_sternum_slice; /**< with last_sternum_slice and slice_spacing_mm (> 0): the sternal length */
  double last_sternum_slice;
  double slice_spacing_mm;
  double depression_mm; /**< sternal depression, 0 to 60 */
  double torsion_deg;   /**< sternal torsion, -45 to 45 (positive: the right edge deeper) */
  double
      ct_haller_index; /**< as measured on the CT, 0 if unknown; given, the spine is placed to give it back */
} PectusPlannerPatient;

/** Materials, mesh and skin settings. Fill with default_options() first, then change what you need. */
typedef struct PectusPlannerOptions {
  double sternum_youngs_modulus_mpa;   /**< default 11500 (dissertation Table 1) */
  double sternum_poisson_ratio;        /**< default 0.3 */
  double rib_youngs_modulus_mpa;       /**< default 5000 */
  double rib_poisson_ratio;            /**< default 0.3 */
  double cartilage_youngs_modulus_mpa; /**< default 80, calibrated in vivo (Table 1: 20); set per patient */
  double cartilage_poisson_ratio;      /**< default 0.4 */
  double contact_width_mm;             /**< cranio-caudal width of the bar's contact patch, default 12 */
  double rib_cell_length_mm;           /**< mesh: cell length along ribs, 2 to 20, default 6 */
  int32_t sternum_cells_along;         /**< mesh: cells along the sternum, default 34 */
  double soft_tissue_mm;               /**< skin: soft-tissue thickness over the bones, default 15 */
  int32_t skin_rows;                   /**< skin grid rows (top to bottom), default 64 */
  int32_t skin_columns;                /**< skin grid columns (right to left), default 96 */
} PectusPlannerOptions;

/** What the generated ribcage measures, the way the CT was measured; and the fit that made it. */
typedef struct PectusPlannerMeasurements {
  double width_mm, depth_mm, sternal_length_mm, depression_mm, torsion_deg;
  double inner_width_mm;      /**< between the inner surfaces of the ribs on the slice */
  double sternum_to_spine_mm; /**< posterior sternum to anterior vertebral body on the slice */
  double haller_index;        /**< inner_width_mm / sternum_to_spine_mm */
  double slice_z_mm;          /**< height of the slice of deepest depression */
  double fit_residual_mm;     /**< largest difference between a target and what the ribcage measures */
  int32_t fit_converged;      /**< 1 if every residual is within the fit's tolerance */
  int32_t fit_iterations;
  int64_t nodes, tets; /**< of the quadratic tetrahedral mesh */
  int64_t free_dofs;
  double factorization_seconds; /**< assembly and Cholesky factorisation, s (wall) */
} PectusPlannerMeasurements;

/** A triangle mesh owned by the planner. */
typedef struct PectusPlannerMesh {
  int64_t num_vertices;
  const double* vertices; /**< num_vertices by 3, mm */
  int64_t num_faces;
  const int32_t* faces;       /**< num_faces by 3 vertex indices, outward */
  const int32_t* face_labels; /**< num_faces labels (bone: 0 sternum, 1 rib, 2 cartilage), or NULL */
} PectusPlannerMesh;

/** A named point. Labels: "sternal_notch", "manubrium_centre", "sternal_angle", "xiphoid" (the
 *  xiphisternal joint), "xiphoid_tip". */

/** Which landmarks landmarks() gives. */
enum PectusPlannerLandmarkSet {
  PECTUS_PLANNER_BONE_LANDMARKS = 0, /**< on the ribcage (anterior midline of the sternum) */
  PECTUS_PLANNER_SKIN_LANDMARKS = 1, /**< projected forward onto the undeformed skin */
  /** The skin landmarks of the skin without the deformity (skin_surface(..., 1, ...)): the frame to
   *  register every predicted chest in, since the bar moves the real ones. */
  PECTUS_PLANNER_REFERENCE_LANDMARKS = 2
};
typedef struct PectusPlannerLandmark {
  char label[48];
  double position[3]; /**< mm */
} PectusPlannerLandmark;

/** Where the bar pushes and how hard. */
typedef struct PectusPlannerBar {
  double position;        /**< along the sternum from the notch: fraction of the sternal length, or mm */
  int32_t position_in_mm; /**< 1 if `position` is in mm */
  double force_n;         /**< > 0 */
} PectusPlannerBar;

/** Figures of one solved load case. */
typedef struct PectusPlannerCaseResult {
  double sternum_lift_mm;     /**< anterior displacement of the sternum at the slice of deepest depression */
  double max_displacement_mm; /**< over the whole ribcage */
  double bar_level_z_mm;      /**< height at which the bar meets the sternum */
  double contact_area_mm2;
  int64_t contact_faces;
} PectusPlannerCaseResult;

/** Force to lift the sternum by the patient's depression with the bar at one position. */
typedef struct PectusPlannerForceToLift {
  double lift_per_newton_mm; /**< sternal lift under 1 N */
  double force_n;            /**< depression / lift_per_newton_mm */
} PectusPlannerForceToLift;

/** Called as work advances (done of total); may be NULL. */
typedef void (*PectusPlannerProgressFn)(void* user, int64_t done, int64_t total);

/** Summary of a written dataset. */
typedef struct PectusPlannerDatasetSummary {
  int64_t patients, load_cases, results, surface_nodes;
  double seconds;
} PectusPlannerDatasetSummary;

/** How build_basis() compresses the response (fill with zeros for the defaults). */
typedef struct PectusPlannerBasisOptions {
  double tolerance_mm; /**< largest difference from the uncompressed response up to max_force_n; 0: 0.003 */
  double max_force_n;  /**< the largest bar force the tolerance is stated for; 0: 2000 */
} PectusPlannerBasisOptions;

/** What build_basis() built. */
typedef struct PectusPlannerBasisSummary {
  int64_t rank;               /**< modes kept */
  int64_t contact_nodes;      /**< mesh nodes of the sternum's back the bar can load */
  int64_t points;             /**< outputs: bone vertices + skin vertices + skin landmarks */
  int64_t bytes;              /**< held by the basis */
  double truncation_bound_mm; /**< the compression's bound at max_force_n, mm */
  double seconds;             /**< wall time of the build */
} PectusPlannerBasisSummary;

/** How evaluate_emulator() runs (fill with zeros for the defaults; docs/planner.md, "The emulator"). */
typedef struct PectusPlannerEmulatorOptions {
  int32_t inputs;         /**< 0 the fitted patient map (default), 1 the CT measurements, 2 the same with
                               log lengths, 3 both 2 and 0 */
  int32_t scale;          /**< divided out before the components: 0 sternal lift (default), 1 norm, 2 none */
  int32_t max_components; /**< principal components per position at most; 0: 20 */
  int32_t learn_skin;     /**< 1: learn the skin grid directly instead of the mesh's boundary nodes */
  double explained_fraction; /**< components kept to this fraction of the variance; 0: 0.9999 */
} PectusPlannerEmulatorOptions;

/** A method's errors over its leave-one-patient-out cases (the skin grid; a case is one patient, bar
 *  position and force). "Small" cases: FE sternal lift at most 40 mm. */
typedef struct PectusPlannerEmulatorFigures {
  int64_t cases, small_lift_cases;
  double skin_rms_mean_mm, skin_rms_max_mm, skin_rms_within_1mm; /**< small cases; fraction <= 1 mm */
  double skin_p95_mean_mm, skin_p95_max_mm, skin_p95_within_2mm; /**< small cases; per-case 95th percentile */
  double relative_l2_mean, relative_l2_max, relative_l2_within_5pc; /**< all cases; fractions */
  double small_lift_error_mean_mm, small_lift_error_max_mm, small_lift_error_within_1mm;
  double lift_error_mean_mm, lift_error_max_mm; /**< all cases */
  double coverage_2sd; /**< share of all coordinates within the predicted 2 sigma band; -1 if none */
  int32_t worst_skin_rms_patient, worst_relative_l2_patient, worst_lift_patient; /**< index; -1 none */
} PectusPlannerEmulatorFigures;

/** One left-out patient. */
typedef struct PectusPlannerEmulatorPatient {
  char id[64];
  char nearest_patient[64]; /**< the nearest-patient baseline's choice */
  PectusPlannerEmulatorFigures emulator;
  double fit_seconds;     /**< the emulator's fit on the other patients */
  double components_mean; /**< principal components kept, mean over the positions */
} PectusPlannerEmulatorPatient;

/** What evaluate_emulator() measured. */
typedef struct PectusPlannerEmulatorEvaluation {
  int64_t patients, positions, forces, skin_vertices;
  double training_set_seconds; /**< the FE solves of every patient */
  double evaluation_seconds;   /**< the folds */
  PectusPlannerEmulatorFigures emulator, nearest_patient, mean_response;
} PectusPlannerEmulatorEvaluation;

/* ---- version 5: the trainer's types ---- */

/** A haptic device's reading (CHAI3D's generic device in spirit). Scene frame (LPS, mm). */
typedef struct PectusPlannerDeviceState {
  double time_s;              /**< since the session's start */
  double position_mm[3];      /**< the tool's tip */
  double orientation_wxyz[4]; /**< unit quaternion; the tool's axis, handle to tip, is R (0, 0, 1) */
  uint32_t buttons;           /**< bit i: button i pressed */
} PectusPlannerDeviceState;

/** The host's haptic device, called by the plugin's servo thread (trainer_start): `read` gives the state
 *  at `time_s`, `set_force` takes the force (N) and torque (N mm) to render until the next tick. Both are
 *  called once per tick from one thread and must not block. */
typedef struct PectusPlannerDevice {
  void* user;
  void (*read)(void* user, double time_s, PectusPlannerDeviceState* out);
  void (*set_force)(void* user, const double force_n[3], const double torque_nmm[3]);
} PectusPlannerDevice;

/** One servo tick's outcome. */
typedef struct PectusPlannerTrainerTick {
  int64_t tick; /**< ticks of the session so far, this one included */
  double time_s;
  double device_mm[3];            /**< the device's tip (the proxy's goal) */
  double proxy_mm[3];             /**< the introducer's tip as drawn: never inside a surface */
  double axis[3];                 /**< the introducer's axis, handle to tip */
  double force_n[3];              /**< sent to the device */
  double torque_nmm[3];           /**< sent to the device: the shaft's forces about the tip */
  uint32_t organs_touched;        /**< bit 0 bone, bit 1 pericardium, bit 2 lung */
  double pericardium_force_n;     /**< the force the pericardium takes */
  double pericardium_distance_mm; /**< from the proxy to the pericardium */
} PectusPlannerTrainerTick;

/** An intercostal space: side -1 right, +1 left, 0 none; number 1-9 (between rib n and n + 1), 0 none. */
typedef struct PectusPlannerSpace {
  int32_t side, number;
} PectusPlannerSpace;

/** The planned pathway of the introducer's tip (docs/trainer.md, "Planned tunnel"). */
typedef struct PectusPlannerTunnel {
  double entry_port_mm[3], exit_port_mm[3]; /**< centres of the spaces it enters and leaves through */
  PectusPlannerSpace entry, exit;
  double scope_port_mm[3]; /**< where the thoracoscope enters (the right space below the entry) */
  double level_z_mm;       /**< the bar's level: the slice of deepest depression */
  double length_mm;
  int64_t num_points; /**< of the polyline (tunnel_points) */
} PectusPlannerTunnel;

/** A session's scores (docs/trainer.md, "Scores": each a definition over the recorded ticks). */
typedef struct PectusPlannerTrainerScore {
  int64_t ticks;
  double min_pericardium_distance_mm, time_near_pericardium_s;
  int32_t pericardial_contacts;
  double peak_pericardium_force_n, peak_force_n, path_length_mm, rms_tunnel_deviation_mm;
  PectusPlannerSpace entry, exit;
  int32_t entry_as_planned, exit_as_planned;
  double total_time_s;
  double score; /**< 100 minus the penalties, at least 0 */
} PectusPlannerTrainerScore;

/** The servo loop's timing over a run (trainer_stop). */
typedef struct PectusPlannerLoopStatistics {
  int64_t ticks, late_ticks;
  double period_mean_ms, period_p50_ms, period_p99_ms, period_max_ms;
  double tick_p50_us, tick_p99_us, tick_max_us;
} PectusPlannerLoopStatistics;

/** The thoracoscope's camera: it pivots at the scope port, tip = port + R (0, 0, insertion); a 30 degree
 *  oblique optic with an 80 degree horizontal field, 640 x 480 pixels (docs/trainer.md). */
typedef struct PectusPlannerScopeView {
  double orientation_wxyz[4]; /**< R: the scope's axis, handle to tip, is R (0, 0, 1) */
  double insertion_mm;
  double eye_mm[3];         /**< the camera at the scope's tip */
  double forward[3], up[3]; /**< the view direction and the image's up, unit */
  double horizontal_fov_deg, vertical_fov_deg;
  int32_t width_px, height_px;
  double focal_px;
} PectusPlannerScopeView;

typedef struct PectusPlanner PectusPlanner;                 /**< opaque */
typedef struct PectusPlannerDeformer PectusPlannerDeformer; /**< opaque: one per thread (version 2) */
typedef struct PectusPlannerTrainer PectusPlannerTrainer;   /**< opaque (version 5) */

/** The plugin's function table. Every function returning int32_t returns a PectusPlannerCode and fills
 *  `status` (which may be NULL if the caller does not want the message). */
typedef struct PectusPlannerInterface {
  uint32_t version;     /**< PECTUS_PLANNER_INTERFACE_VERSION of the plugin; check it before anything else */
  uint32_t struct_size; /**< sizeof(PectusPlannerInterface) in the plugin */
  const char* description; /**< e.g. "pectus planner 0.1.0 (quadratic tetrahedra, CHOLMOD)" */

  /** Fills `options` with the defaults. */
  void (*default_options)(PectusPlannerOptions* options);

  /** Reads `patient` from a patient table (CSV: patient, width_mm, sternal_length_mm, depth_mm,
   *  depression_mm, optional haller_index, magnification, torsion_deg). */
  int32_t (*read_patient)(const char* table_path, const char* patient, PectusPlannerPatient* out,
                          PectusPlannerStatus* status);

  /** Builds the patient's ribcage, fits it to the measurements, meshes it with quadratic tetrahedra,
   *  assembles and factorises the stiffness once, and builds the skin. On success *out is a planner to
   *  pass to destroy(). `options` may be NULL (defaults). */
  int32_t (*create)(const PectusPlannerPatient* patient, const PectusPlannerOptions* options,
                    PectusPlanner** out, PectusPlannerStatus* status);
  /** Frees a planner (NULL is allowed). */
  void (*destroy)(PectusPlanner* planner);

  int32_t (*measurements)(const PectusPlanner* planner, PectusPlannerMeasurements* out,
                          PectusPlannerStatus* status);
  /** The bone surface (corner nodes of the mesh boundary; labels: material region per face). */
  int32_t (*bone_surface)(const PectusPlanner* planner, PectusPlannerMesh* out, PectusPlannerStatus* status);
  /** The skin over the chest wall, a rows by columns grid: as measured (`without_deformity` 0), or as the
   *  same ribcage without depression and torsion would carry it (1; same faces, vertex by vertex). */
  int32_t (*skin_surface)(const PectusPlanner* planner, int32_t without_deformity, PectusPlannerMesh* out,
                          PectusPlannerStatus* status);
  /** The landmarks of `set` (PectusPlannerLandmarkSet). Writes at most `capacity` into `out` and the
   *  number there are into *count. */
  int32_t (*landmarks)(const PectusPlanner* planner, int32_t set, PectusPlannerLandmark* out,
                       int32_t capacity, int32_t* count, PectusPlannerStatus* status);

  /** Solves `count` load cases on the one factorisation. Each output may be NULL; otherwise it holds
   *  count blocks, one per case in order:
   *   bone_positions  count x bone vertices x 3: deformed bone surface vertices, mm
   *   skin_positions  count x skin vertices x 3: deformed skin vertices, mm
   *   skin_landmarks  count x landmark count x 3: skin landmarks of the deformed skin, mm
   *   results         count figures. */
  int32_t (*solve)(const PectusPlanner* planner, const PectusPlannerBar* bars, int64_t count,
                   double* bone_positions, double* skin_positions, double* skin_landmarks,
                   PectusPlannerCaseResult* results, PectusPlannerStatus* status);

  /** Force to lift the sternum by the patient's depression at each of `count` bar positions
   *  (bars[i].force_n is ignored). */
  int32_t (*force_to_lift)(const PectusPlanner* planner, const PectusPlannerBar* bars, int64_t count,
                           PectusPlannerForceToLift* out, PectusPlannerStatus* status);

  /** The dissertation's dataset: every patient of `table_path` x 3 bar positions (0.65, 0.75, 0.85 of the
   *  sternal length) x 8 forces (50, 70, 100, 200, 400, 800, 1500, 2000 N), surface-node displacements
   *  written as one HDF5 file at `output_path` (replaced only when complete). With `basis` (version 2;
   *  NULL: none) each patient's exact response basis too, for load_basis(). */
  int32_t (*write_dataset)(const char* table_path, const char* output_path,
                           const PectusPlannerOptions* options, const struct PectusPlannerBasisOptions* basis,
                           PectusPlannerProgressFn progress, void* progress_user,
                           PectusPlannerDatasetSummary* out, PectusPlannerStatus* status);

  /* ---- version 2: the exact response basis and the real-time deform call ---- */

  /** Builds (or rebuilds) the planner's exact response basis: the bar solved at finely sampled levels on
   *  the one factorisation, compressed to `options` (NULL: defaults). Seconds per patient. Deformers made
   *  before a rebuild must be destroyed first. `out` may be NULL. */
  int32_t (*build_basis)(PectusPlanner* planner, const PectusPlannerBasisOptions* options,
                         PectusPlannerBasisSummary* out, PectusPlannerStatus* status);
  /** Takes the planner's patient's basis from a dataset written with bases (write_dataset) instead of
   *  building it: milliseconds instead of seconds. BAD_INPUT, naming the file, if the file has none for
   *  this patient or it was built for another planner (mesh, skin, contact width or materials differ). */
  int32_t (*load_basis)(PectusPlanner* planner, const char* dataset_path, PectusPlannerBasisSummary* out,
                        PectusPlannerStatus* status);
  /** A deformer for one thread: its buffers sized once here. Needs build_basis() first. It refers to
   *  the planner, which must outlive it. */
  int32_t (*create_deformer)(const PectusPlanner* planner, PectusPlannerDeformer** out,
                             PectusPlannerStatus* status);
  /** Frees a deformer (NULL is allowed). */
  void (*destroy_deformer)(PectusPlannerDeformer* deformer);
  /** The chest under one bar, from the basis: deformed bone vertices (bone vertices x 3), skin vertices
   *  (skin vertices x 3) and skin landmarks (landmark count x 3), each NULL if not wanted, and the sternal
   *  lift (mm; NULL if not wanted). Real time: no allocation, no lock, no exception, no I/O (a
   *  fraction of a millisecond for the whole surface). Returns USAGE (outputs untouched) for a bar off
   *  the sternum or a non-finite value; `status` may be NULL. Matches solve() to 0.01 mm. */
  int32_t (*deform)(PectusPlannerDeformer* deformer, const PectusPlannerBar* bar, double* bone_positions,
                    double* skin_positions, double* skin_landmarks, double* sternum_lift_mm,
                    PectusPlannerStatus* status);
  /** The force that lifts the sternum by `lift_mm` with the bar at `bar->position` (bar->force_n is
   *  ignored), from the basis: real time, as deform(). */
  int32_t (*lift_force)(PectusPlannerDeformer* deformer, const PectusPlannerBar* bar, double lift_mm,
                        double* force_n, PectusPlannerStatus* status);

  /* ---- version 3: the learned emulator ---- */

  /** The response emulator left one patient out at a time: every patient of `table_path` (or those of
   *  `patients`, ids separated by commas; NULL: all) solved once by FE with a 1 N bar at the
   *  dissertation's three positions, then per patient the emulator fitted on the others predicts its
   *  load cases (3 positions x 8 forces) from its measurements alone, beside the nearest-patient and
   *  mean-response baselines on the same folds. Minutes for 62 patients. `per_patient` (may be NULL)
   *  receives at most `capacity` patients, in the table's order. `progress` counts the FE solves and
   *  then the folds (2 per patient). */
  int32_t (*evaluate_emulator)(const char* table_path, const char* patients,
                               const PectusPlannerOptions* options,
                               const PectusPlannerEmulatorOptions* emulator, PectusPlannerProgressFn progress,
                               void* progress_user, PectusPlannerEmulatorEvaluation* out,
                               PectusPlannerEmulatorPatient* per_patient, int64_t capacity,
                               PectusPlannerStatus* status);

  /* ---- version 4: the basis as a table, for a host that evaluates it itself ---- */

  /** The basis's modes U_r (orthonormal columns, to about 1e-3): `rows` = 3 x (bone vertices + skin vertices
   * + skin landmarks), the output points of deform() in its order (x, y, z of each); `rank` columns. Always
   *  gives the sizes (each may be NULL); writes the modes row after row (rows x rank, float32) into
   *  `modes` when it is not NULL, or USAGE if `capacity` (floats) is smaller. Needs build_basis() or
   *  load_basis(). */
  int32_t (*basis_modes)(const PectusPlanner* planner, float* modes, int64_t capacity, int64_t* rows,
                         int64_t* rank, PectusPlannerStatus* status);
  /** The coefficients per newton c (rank values; NULL if not wanted) and the sternal lift per newton (mm/N;
   *  NULL if not wanted) of a bar at `bar->position` (bar->force_n is ignored): deform() gives the rest
   *  positions plus force_n x U_r c. Real time, as deform(): USAGE, outputs untouched, off the sternum. */
  int32_t (*basis_coefficients)(PectusPlannerDeformer* deformer, const PectusPlannerBar* bar,
                                double* coefficients, double* lift_per_n, PectusPlannerStatus* status);

  /* ---- version 5: the Nuss trainer ---- */

  /** The trainer of the planner's patient: its scene (seconds: the organs placed from the fitted ribcage,
   *  the collision grids) and an empty session for `introducer` ("small", "medium", "large"; NULL:
   *  "medium") with room for `capacity_ticks` ticks (0: ten minutes at 1 kHz; ticks beyond are run but not
   *  recorded). It copies what it needs: the planner may be destroyed first. */
  int32_t (*trainer_create)(const PectusPlanner* planner, const char* introducer, int64_t capacity_ticks,
                            PectusPlannerTrainer** out, PectusPlannerStatus* status);
  /** Stops its servo thread if running and frees it (NULL is allowed). */
  void (*trainer_destroy)(PectusPlannerTrainer* trainer);
  /** A scene mesh: 0 the bones, 1 the pericardium, 2 the right lung, 3 the left lung (closed, outward;
   *  the bones' labels: 0 sternum, k left rib k, -k right rib k, each with its cartilage). */
  int32_t (*trainer_mesh)(const PectusPlannerTrainer* trainer, int32_t part, PectusPlannerMesh* out,
                          PectusPlannerStatus* status);
  /** The planned tunnel; its polyline (num_points x 3, right port first) into `points` if not NULL and
   *  `capacity` (points) suffices (USAGE otherwise). */
  int32_t (*trainer_tunnel)(const PectusPlannerTrainer* trainer, PectusPlannerTunnel* out, double* points,
                            int64_t capacity, PectusPlannerStatus* status);
  /** Starts a new session (the record emptied; the proxy placed at the first tick's device tip). Not while
   *  the servo thread runs (USAGE). */
  int32_t (*trainer_reset)(PectusPlannerTrainer* trainer, PectusPlannerStatus* status);
  /** One servo tick of the session in the caller's thread, the device's state given (its time_s never
   *  below the last tick's): the proxy moved, the force computed into `out`, the tick recorded. Real time:
   *  no allocation, lock, exception or I/O. USAGE while the servo thread runs or for a non-finite state. */
  int32_t (*trainer_tick)(PectusPlannerTrainer* trainer, const PectusPlannerDeviceState* state,
                          PectusPlannerTrainerTick* out, PectusPlannerStatus* status);
  /** Starts a new session on the plugin's servo thread: `rate_hz` ticks a second (0: 1000) on an absolute
   *  schedule, each reading `device` and sending it the force. The device must stay valid until
   *  trainer_stop(). */
  int32_t (*trainer_start)(PectusPlannerTrainer* trainer, const PectusPlannerDevice* device, double rate_hz,
                           PectusPlannerStatus* status);
  /** Stops the servo thread (nothing if not running); its timing into `out` (may be NULL). */
  int32_t (*trainer_stop)(PectusPlannerTrainer* trainer, PectusPlannerLoopStatistics* out,
                          PectusPlannerStatus* status);
  /** The session's latest tick, from any thread while the servo thread runs (never blocks it). USAGE
   *  before the first tick. */
  int32_t (*trainer_latest)(const PectusPlannerTrainer* trainer, PectusPlannerTrainerTick* out,
                            PectusPlannerStatus* status);
  /** The scores of the ticks recorded so far (from any thread, the servo thread running or not). USAGE
   *  for fewer than two ticks. */
  int32_t (*trainer_score)(const PectusPlannerTrainer* trainer, PectusPlannerTrainerScore* out,
                           PectusPlannerStatus* status);
  /** Writes the session's record (ticks so far, docs/trainer.md "Session records") atomically to `path`. */
  int32_t (*trainer_write_record)(const PectusPlannerTrainer* trainer, const char* path,
                                  PectusPlannerStatus* status);
  /** Replays the record at `path` in this trainer's scene (it must be this patient's) and scores it: the
   *  session's scores bit for bit if it is this session's record. */
  int32_t (*trainer_replay)(const PectusPlannerTrainer* trainer, const char* path,
                            PectusPlannerTrainerScore* out, PectusPlannerStatus* status);
  /** The thoracoscope's view at the scope port: with `orientation_wxyz` (the tracked scope's R) as given;
   *  with NULL aimed so that the oblique view's centre looks at `target_mm` (NULL: the proxy of the latest
   *  tick), the image's up as near the patient's head as it can be. `insertion_mm` from the port to the
   *  tip (> 0). */
  int32_t (*trainer_scope_view)(const PectusPlannerTrainer* trainer, const double* orientation_wxyz,
                                const double* target_mm, double insertion_mm, PectusPlannerScopeView* out,
                                PectusPlannerStatus* status);

  /* ---- version 6: the FE dataset one patient at a time, for a task farm ---- */

  /** One patient of write_dataset's dataset: row `row` (0-based, in the table's order) of `table_path`,
   *  its 24 load cases, force to lift and, with `basis` (NULL: none), its exact response basis, written
   *  as a one-patient dataset at `part_path`, committed atomically (a temporary file renamed into place).
   *  Calls are independent: the parts of a table may be made in any order, in any process. `out` (may be
   *  NULL): the part's figures (1 patient) and its own wall time, without the generic ribcage of the
   *  options, which a process builds once, in its first call (version 7; the host's time of the call less
   *  this is that setup). */
  int32_t (*write_dataset_part)(const char* table_path, int64_t row, const char* part_path,
                                const PectusPlannerOptions* options,
                                const struct PectusPlannerBasisOptions* basis,
                                PectusPlannerDatasetSummary* out, PectusPlannerStatus* status);
  /** The dataset from `count` parts (write_dataset_part) in the order given, their data copied as stored:
   *  the bytes write_dataset writes for those patients, whatever process made each part. Written at
   *  `output_path`, replaced only when complete. BAD_INPUT naming the part that is not one, or was made
   *  with other options than the first. `out` may be NULL. */
  int32_t (*assemble_dataset)(const char* const* part_paths, int64_t count, const char* output_path,
                              PectusPlannerDatasetSummary* out, PectusPlannerStatus* status);
} PectusPlannerInterface;

/** The one exported symbol: the plugin's function table (static storage; never NULL). */
typedef const PectusPlannerInterface* (*PectusPlannerEntryFn)(void);

#ifdef __cplusplus
}
#endif

#endif /* PECTUS_PLANNER_API_H_ */
