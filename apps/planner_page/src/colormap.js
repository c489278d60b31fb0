// Colour-blind-safe maps (cividis, the default, and viridis): 9 stops each, interpolated linearly.
const maps = {
  cividis: [[0, 34, 78], [19, 54, 110], [64, 77, 107], [98, 99, 110], [124, 123, 120], [153, 149, 118], [186, 176, 108], [220, 205, 89], [255, 234, 70]],
  viridis: [[68, 1, 84], [71, 44, 122], [59, 81, 139], [44, 113, 142], [33, 144, 141], [39, 173, 129], [92, 200, 99], [170, 220, 50], [253, 231, 37]],
};
export const colormapNames = Object.keys(maps);

/// RGB in [0, 1] of `t` in [0, 1] on map `name`.
export function colour(name, t, out = [0, 0, 0]) {
  const stops = maps[name] ?? maps.cividis;
  const x = Math.min(Math.max(Number.isFinite(t) ? t : 0, 0), 1) * (stops.length - 1);
  const i = Math.min(Math.floor(x), stops.length - 2), a = x - i;
  for (let k = 0; k < 3; ++k) out[k] = ((1 - a) * stops[i][k] + a * stops[i + 1][k]) / 255;
  return out;
}

/// A labelled colour bar: `limit` mm either side of zero (negative: still sunken; positive: in front).
export function drawColourBar(element, name, limit) {
  const canvas = document.createElement('canvas');
  canvas.width = 220;
  canvas.height = 14;
  const g = canvas.getContext('2d');
  for (let x = 0; x < canvas.width; ++x) {
    const [r, gr, b] = colour(name, x / (canvas.width - 1));
    g.fillStyle = `rgb(${r * 255},${gr * 255},${b * 255})`;
    g.fillRect(x, 0, 1, canvas.height);
  }
  element.replaceChildren();
  const title = document.createElement('div');
  title.textContent = 'predicted − average chest (mm)';
  const labels = document.createElement('div');
  labels.style.display = 'flex';
  labels.style.justifyContent = 'space-between';
  for (const v of [-limit, -limit / 2, 0, limit / 2, limit]) {
    const span = document.createElement('span');
    span.textContent = (v > 0 ? '+' : '') + v.toFixed(limit < 4 ? 1 : 0);
    labels.append(span);
  }
  element.append(title, canvas, labels);
}
