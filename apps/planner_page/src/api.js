// The server's API (docs/planner.md, "Planner in the browser"): the token of the page's URL goes with
// every request as the X-Pectus-Token header.
const token = new URLSearchParams(location.search).get('token') ?? '';

export async function request(path, options = {}) {
  const response = await fetch(path, { ...options, headers: { 'X-Pectus-Token': token, ...(options.headers ?? {}) } });
  if (!response.ok) {
    let message = `${response.status}`;
    try {
      message = (await response.json()).error ?? message;
    } catch {}
    throw new Error(`${path}: ${message}`);
  }
  return response;
}
export const getJson = async (path) => (await request(path)).json();
export const getBinary = async (path) => (await request(path)).arrayBuffer();
export const postJson = async (path, body) =>
  (await request(path, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) })).json();
