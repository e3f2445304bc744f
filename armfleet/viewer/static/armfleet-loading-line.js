// armfleet: the loading line over the scene, and the page's report that it shows the scene.
//
// The server sends {type: "armfleet_status", text, serial} after every command sent
// before it: while meshes are on their way the line names them, and an empty line
// comes once they are all here. The page then hides the line and, once a frame with the
// scene has been painted, answers "armfleet:shown:<serial>", which tells the server (e.g.
// a replay waiting for a browser) that this page shows the scene. (Answering at once let
// a loaded machine's replay start before the page had drawn its opening.)
function armfleetLoadingLine(viewer, element) {
  const handle = viewer.handle_command.bind(viewer);
  viewer.handle_command = function (command) {
    if (!command || command.type !== "armfleet_status") {
      handle(command);
      return;
    }
    element.textContent = command.text;
    element.hidden = command.text === "";
    if (command.text !== "") {
      return;
    }
    // The first callback runs before the next paint, the second after it.
    requestAnimationFrame(() =>
      requestAnimationFrame(() => {
        const socket = viewer.connection;
        if (socket && socket.readyState === WebSocket.OPEN) {
          socket.send("armfleet:shown:" + command.serial);
        }
      }),
    );
  };
}
