"""Seeing a run: the headless MP4 video and the Foxglove 3D scene of the MCAP log.

- `samples`: what one video frame needs (the scene's full qpos, stance flags, task label), the
  same values whether they come live from the loop or from the log's ``/sim/qpos`` topic;
- `view_log`: what the closed loop writes so Foxglove shows the run (robot geometry, objects,
  fixtures, footholds, contact forces, MPC prediction, torque ratios);
- `gl`, `renderer`, `camera`, `video`: MuJoCo's offscreen renderer on software OpenGL, the
  trunk-tracking camera and the MP4 writer; `from_log`: the video of a saved log.

Modules that need OpenGL are imported on demand: importing this package opens no GL context.
"""
