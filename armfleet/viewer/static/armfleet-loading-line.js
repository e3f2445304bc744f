// armfleet: the loading line over the scene, and the page's report that it shows the scene.
//
// The server sends {type: "armfleet_status", text, serial} after every command sent
// before it: while meshes are on their way the line names them, and an empty line
// comes once they are all here. The page then hides the line and, at the first frame it
// draws after that, answers "armfleet:shown:<serial>", which tells the server (e.g. a
// replay waiting for a browser) that this page shows the scene. (Drawing waits while
// meshes arrive, armfleet-mesh-cache.js: answering at once, or a frame later, let a
// loaded machine's replay start before the page had drawn its opening.)
function armfleetLoadingLine(viewer, element) {
  let awaited = null; // the serial to report at the next drawn frame
  const draw = viewer.renderer.render.bind(viewer.renderer);
  viewer.renderer.render = function (scene, camera) {
    draw(scene, camera);
    if (awaited === null) return;
    const socket = viewer.connection;
    if (socket && socket.readyState === WebSocket.OPEN) {
      socket.send("armfleet:shown:" + awaited);
    }
    awaited = null;
  };
  const handle = viewer.handle_command.bind(viewer);
  viewer.handle_command = function (command) {
    if (!command || command.type !== "armfleet_status") {
      handle(command);
      return;
    }
    element.textContent = command.text;
    element.hidden = command.text === "";
    awaited = command.text === "" ? command.serial : null;
    if (awaited !== null) viewer.set_dirty(); // a frame comes even if nothing else changes
  };
}
