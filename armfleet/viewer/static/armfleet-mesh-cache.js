// armfleet: unroll batched live updates, and parse each mesh file once per page.
//
// Every arm of a fleet loads the same mesh files (a Panda's are ~10 MB of
// Collada text). The server tags a mesh-file object with a digest
// ("armfleet_mesh") and sends its text only once per page; later objects with
// the same digest come without it and get a clone of the first one parsed,
// which shares its geometry and materials.
function armfleetCacheMeshes(viewer) {
  // Live updates come batched: one message holding an array of commands.
  const handle = viewer.handle_command.bind(viewer);
  viewer.handle_command = function (command) {
    if (Array.isArray(command)) command.forEach(handle);
    else handle(command);
  };
  const parsed = new Map();
  // While meshes arrive, drawing waits: a frame of software WebGL can take
  // longer than parsing a mesh, and would hold up every message behind it.
  let lastMeshAt = -Infinity;
  const render = viewer.render.bind(viewer);
  viewer.render = function () {
    if (performance.now() - lastMeshAt > 150) render();
  };
  const parse = viewer.set_object_from_json.bind(viewer);
  viewer.set_object_from_json = function (path, json) {
    const inner = json && json.object;
    const digest = inner && inner.armfleet_mesh;
    if (digest === undefined) {
      parse(path, json);
      return;
    }
    lastMeshAt = performance.now();
    const known = parsed.get(digest);
    if (known !== undefined) {
      viewer.set_object(path, known.clone());
      viewer.set_dirty();
      return;
    }
    if (!inner.data || inner.data.length === 0) {
      console.error("armfleet: mesh " + digest + " was never sent");
      return;
    }
    const place = viewer.set_object;
    viewer.set_object = function (where, object) {
      parsed.set(digest, object);
      viewer.set_object = place;
      place.call(viewer, where, object);
    };
    try {
      parse(path, json);
    } finally {
      viewer.set_object = place;
    }
  };
}
