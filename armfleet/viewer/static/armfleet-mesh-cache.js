// armfleet: unroll batched live updates, and parse each mesh file once per page.
//
// Every arm of a fleet loads the same mesh files (a Panda's are ~10 MB of
// Collada text). The server tags a mesh-file object with a digest
// ("armfleet_mesh") and sends its text only once per page; later objects with
// the same digest come without it and get a clone of the first one parsed,
// which shares its geometry and materials.
function armfleetCacheMeshes(viewer) {
  // A new mesh stands at the origin until its node's set_transform comes (an arm's
  // meshes come first, then their poses): until then it is "unplaced", and no frame is
  // drawn, which showed a half-built arm at the wrong place.
  const unplaced = new Set();
  const forget = function (prefix) {
    for (const key of [...unplaced]) if (key === prefix || key.startsWith(prefix + "/")) unplaced.delete(key);
  };
  // Live updates come batched: one message holding an array of commands.
  const handleOne = viewer.handle_command.bind(viewer);
  const handle = function (command) {
    handleOne(command);
    if (command && command.type === "set_transform") unplaced.delete(pathKey(command.path));
    else if (command && command.type === "delete") forget(pathKey(command.path));
  };
  viewer.handle_command = function (command) {
    if (Array.isArray(command)) command.forEach(handle);
    else handle(command);
  };
  const parsed = new Map();
  // While meshes arrive, drawing waits: a frame of software WebGL can take
  // longer than parsing a mesh, and would hold up every message behind it.
  // A mesh never placed holds drawing up for 2 s at most.
  let lastMeshAt = -Infinity;
  const render = viewer.render.bind(viewer);
  viewer.render = function () {
    const quiet = performance.now() - lastMeshAt;
    if (quiet > 150 && (unplaced.size === 0 || quiet > 2000)) render();
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
    unplaced.add(pathKey(path));
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

// "/meshcat/a/b", "meshcat/a/b/" and ["meshcat", "a", "b"] all name node "meshcat/a/b".
function pathKey(path) {
  const parts = Array.isArray(path) ? path : String(path || "").split("/");
  return parts.filter((part) => part.length > 0).join("/");
}
