// The page's one state object (STYLE 12): every view draws from it, every control changes it through
// set(); a test sets it and reads the figures the same way (window.pectus in main.js).
export const state = {
  patients: [],
  patientId: null,
  info: null, // /api/patients/ID: counts, landmarks, basis layout, T_average_patient
  average: null, // /api/average plus its mesh arrays
  bar: { position: 0.85, force: 200 }, // scenario A: fraction of the sternal length from the notch, N
  compareMm: 20, // scenario B: this many mm nearer the notch
  view: { bone: true, skin: true, average: false, landmarks: true, map: true, opacity: 0.45, colormap: 'cividis' },
  live: null, // from the basis, every frame: { positionMm, liftMm, liftPerN, forceToLift, beyondLinear, updateMs }
  plan: null, // the server's exact figures for `bar` (/api/score: scenarios A and B as `pectus plan --report` scores them)
  planFor: null, // the bar the plan was made for
  search: null, // the server's best-placement search
  dragging: false, // the bar is being dragged in the view
  // The trainer (trainer.js): its session, scene (/api/trainer/start), the device's target (mm, patient
  // frame), the latest tick, the scope's view, the score so far, and the report once finished.
  trainer: { session: null, info: null, target: null, tick: null, scope: null, score: null, report: null, busy: '', error: '' },
  busy: '',
  error: '',
};

const listeners = [];
/// Calls `view(state)` after every change.
export function subscribe(view) {
  listeners.push(view);
}
/// Puts `patch` into the state (`view` is merged: a control changes one of its switches) and lets every
/// view redraw.
export function set(patch) {
  for (const [key, value] of Object.entries(patch)) state[key] = key === 'view' ? { ...state.view, ...value } : value;
  for (const view of listeners) view(state);
}
/// The bar position in mm from the notch.
export function positionMm(s = state) {
  return s.bar.position * (s.info ? s.info.sternal_length_mm : 0);
}
