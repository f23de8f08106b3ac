// The page's test hooks (hub/view/frames.py): `window.planthub`, read by the browser test to
// see what the page saw and drew without scraping pixels. The contract keys are connected,
// frames, tick, bodies(), events and figures; hello, state, scene and results are extras, and
// playback, for a recorded run.

export function installHooks(bodiesNow) {
  const hooks = {
    connected: false,   // the WebSocket is open
    frames: 0,          // frames rendered (renderer.render calls)
    tick: -1,           // tick of the newest bodies message received; -1 before the first
    time: null,         // its plant time, s
    bodies: () => bodiesNow(),   // {"<id>": [x, y, z]}: drawn, interpolated positions of the bodies in play
    events: [],         // every [tick, slot, detail] row seen, oldest first
    figures: null,      // the last figures map {tick, time, wall, rtf, sections}
    hello: null,        // the hello message
    state: null,        // the last state map {state, tick, time, reason}
    scene: null,        // the scene document drawn
    results: [],        // command results {id, ok, tick, error}, oldest first
    playback: null,     // a recorded run's playback: {time: plant s drawn, playing, speed}; null: a live run
    faults: null,       // the last faults board (an instructor's page only)
    checkpoints: null,  // the last checkpoints message {tick, time, rate, checkpoints}: the panel's timeline
    exercise: null,     // the exercise as shown: {task, goals, score, …, ended}
    labels: () => [],   // the name tags shown now: [{object, kind}]
    lost: [],           // ids of followed bottles the camera let go of when they left
  };
  window.planthub = hooks;
  return hooks;
}
