"""The page: a viser scene of the map, its SOLM, plans, flights, replays and a recorded run,
with the controls that query lf3pm (a cell's evaluation, plans between clicked poses, a recorded
scan over the map beside its simulation). Every action goes through
lf3pm's public API and the arrays of lf3pm.view.layers; an error is shown in the page,
never raised into viser's threads."""

from __future__ import annotations

import html
import math
import sys
import threading
from contextlib import contextmanager

import numpy as np

from lf3pm.config import DEFAULTS, GuidanceConfig, PlannerConfig
from lf3pm.errors import CorruptStoreError, Lf3pmError, StorageError
from lf3pm.grid import Space
from lf3pm.pose import pose_matrix
from lf3pm.view import layers
from lf3pm.view.inputs import ViewInputs, check_host, check_port, read_scan

#: Colours (RGB) of what the page draws besides colour-mapped layers.
PLAN_COLORS = [(230, 60, 60), (40, 120, 255), (250, 160, 20), (150, 60, 200), (20, 170, 120)]
GUIDED, UNGUIDED = (255, 80, 200), (255, 255, 255)
TRUTH = (200, 200, 200)
SCAN = (255, 40, 40)
#: A recorded run: its reference path, a chosen scan's real points and the simulated scan
#: at the same pose.
# Magenta and black: colours the map's height colouring (turbo) does not use.
RUN_PATH, REAL_POINTS, SIMULATED_POINTS = (255, 255, 255), (255, 0, 255), (0, 0, 0)
#: Sizes (m) of an audited scan's marker and of a shown scan's points.
MARKER_SIZE, SCAN_POINT_SIZE = 0.35, 0.06
#: The click action that chooses a recorded scan (offered with an audit).
CHOOSE_SCAN = "choose a scan"
ARROWS = [(255, 0, 0), (255, 150, 0), (255, 230, 0)]  # weakest first
#: Seconds between two footprints drawn along a trajectory.
FOOTPRINT_EVERY_S = 2.0
#: Screen widths (pixels) of the lines drawn. A replay runs along its plan: the plan is a
#: wide band, the replay's truth and estimate thin lines on it, so that neither hides the
#: other; plans given together are nested, each PLAN_STEP narrower than the one before
#: and a little above it, so that where they share a path each keeps a rim.
PLAN_WIDTH, PLAN_STEP, TRUTH_WIDTH, ESTIMATE_WIDTH = 9.0, 3.0, 1.5, 3.0
#: A flight's tube is see-through, so that a replay's lines along it stay visible inside.
FLIGHT_OPACITY = 0.55
#: Length and radius (m) of the body's axes drawn along a flight (x red, y green, z blue).
AXES_LENGTH, AXES_RADIUS = 0.5, 0.025
#: Where the page is served unless told otherwise (this machine only).
DEFAULT_HOST, DEFAULT_PORT = "127.0.0.1", 8080


class ViewApp:
    """A running viewer (:func:`serve` starts it): ``server`` is its viser server, ``port``
    the port it serves on, ``stop()`` ends it. ``status`` holds the last message shown
    (for tests); an error met while serving stays in the panel until the action that met
    it succeeds. ``solm_node`` is the SOLM's layer drawn, ``flight_nodes`` each flight's
    (tube, body axes) (None for a hover's tube) and ``flight_text`` their figures."""

    def __init__(
        self,
        inputs: ViewInputs,
        *,
        host: str,
        port: int,
        robot=None,
        guidance: GuidanceConfig | None = None,
        sensor: str | None = None,
        planner: PlannerConfig | None = None,
        z: float | None = None,
    ):
        import viser

        from lf3pm.trajectory.robots import Robot

        self.inputs = inputs
        self.robot = robot if robot is not None else Robot.from_config(DEFAULTS.robot)
        self.guidance = guidance or DEFAULTS.guidance
        self.planner_config = planner or DEFAULTS.planner
        solm = inputs.solm
        self.sensor = sensor or (solm.attrs.get("sensor") if solm is not None else DEFAULTS.sensor)
        # The body the SOLM's obstacle mask was built for.
        self.footprint_radius = float(
            solm.attrs.get("robot_radius", DEFAULTS.solm.robot_radius)
            if solm is not None
            else DEFAULTS.solm.robot_radius
        )
        self.status = ""
        self._errors = {}  # the page action that failed: its message, shown in the panel
        self._lock = threading.RLock()  # an action may set a control whose callback runs inside it
        self._rings = {}
        self._planner = None
        self._start = self._goal = None
        self._ground = None
        # The SOLM's cells are drawn as squares facing the camera, res wide: lines drawn
        # this far above the ground stay in front of them.
        self._above_layer = 0.5 * (solm.grid_spec.res if solm is not None else 0.0) + 0.15
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        try:
            # viser moves to the next port when the one asked for was taken since it was checked.
            if port != 0 and self.server.get_port() != port:
                raise Lf3pmError(f"port {port} on {host} is in use: choose another port")
            self.server.scene.set_up_direction("+z")
            self.error_text = self.server.gui.add_html("", visible=False)
            self._add_map()
            if solm is not None:
                self._add_solm_controls(z)
            self._add_given_plans()
            self._add_flights()
            self._add_replays()
            self._add_run()
            self._add_click_controls()
            self._set_camera()
        except BaseException:
            self.server.stop()  # nothing half-built keeps serving
            raise

    @property
    def port(self) -> int:
        """The port the page is served on (the one taken when :func:`serve` was given 0)."""
        return self.server.get_port()

    # -- what is given -------------------------------------------------------------------

    def _add_map(self) -> None:
        points = self.inputs.world.points
        self._map_points, self._map_colors = layers.map_cloud(points)
        self._map_point_size = max(0.03, 1.5 * float(self.inputs.world.index.median_spacing))
        lo, hi = self.inputs.world.bounds
        gui = self.server.gui
        gui.add_markdown(
            f"**Map** `{self.inputs.world.source}`: {len(self._map_points):,} of "
            f"{len(points):,} points shown, coloured by height"
        )
        # Indoors the ceiling hides everything under it: cut the map below it.
        bottom, top = math.floor(lo[2] * 10) / 10, math.ceil(hi[2] * 10) / 10
        self.map_ceiling = gui.add_slider("hide the map above (m)", min=bottom, max=top, step=0.1, initial_value=top)
        self.map_ceiling.on_update(lambda event: self._guarded(self._draw_map, event.client))
        self._draw_map()

    def _draw_map(self, client=None) -> None:
        keep = self._map_points[:, 2] <= self.map_ceiling.value
        with self._busy(client, "drawing the map"):
            self.server.scene.add_point_cloud(
                "/map",
                self._map_points[keep],
                self._map_colors[keep],
                point_size=self._map_point_size,
                point_shape="square",
                point_shading="flat",
            )

    def _add_solm_controls(self, z: float | None = None) -> None:
        solm, gui = self.inputs.solm, self.server.gui
        g = solm.grid_spec
        with gui.add_folder("SOLM"):
            text = f"{g.space.upper()} grid, {g.nx} × {g.ny} cells of {g.res:g} m"
            if not g.space.ground:
                text += f", {len(g.z_levels)} levels from {min(g.z_levels):.2f} to {max(g.z_levels):.2f} m"
            if g.space.yawed:
                text += f", {g.yaw_bins} yaw bins"
            mount = solm.attrs.get("mount")
            text += f", sensor {solm.attrs.get('sensor')}" + (f" on its mount {mount['name']}" if mount else "")
            gui.add_markdown(text)
            self.channel = gui.add_dropdown("channel", tuple(layers.CHANNELS), initial_value="q_n")
            self.min_yaw = self.layer = self.height = self.level_text = None
            if g.space.yawed:
                self.min_yaw = gui.add_checkbox("min over yaw", initial_value=True)
                self.layer = gui.add_slider(
                    "yaw (deg)",
                    min=0,
                    max=360 - 360 / g.yaw_bins,
                    step=360 / g.yaw_bins,
                    initial_value=0,
                    disabled=True,
                )
                self.min_yaw.on_update(lambda event: self._guarded(self._solm_changed, event.client))
                self.layer.on_update(lambda event: self._guarded(self._solm_changed, event.client))
            if not g.space.ground:
                # The slider in centimetres (levels lie further apart): its box shows 1.0, not 0.996558.
                levels = np.round(np.asarray(g.z_levels, dtype=np.float64), 2)
                shown = layers.nearest_level(g, z) if z is not None else 0
                if len(levels) > 1:  # a slider needs two ends: one level is only read out
                    self.height = gui.add_slider(
                        "height (m)",
                        min=float(levels.min()),
                        max=float(levels.max()),
                        step=max(0.01, float(np.diff(np.sort(levels)).min())),
                        initial_value=float(levels[shown]),
                        marks=tuple(float(v) for v in levels) if len(levels) <= 8 else None,
                    )
                    self.height.on_update(lambda event: self._guarded(self._solm_changed, event.client))
                self.level_text = gui.add_markdown("")
            self.colorbar = gui.add_image(np.zeros(layers.COLORBAR_PIXELS[::-1] + (3,), np.uint8), label="colour bar")
        self.channel.on_update(lambda event: self._guarded(self._solm_changed, event.client))
        self._guarded(self._solm_changed)

    def _yaw_bin(self) -> int | None:
        """The yaw bin the controls select (se2, r3yaw): None for the minimum over yaw."""
        g = self.inputs.solm.grid_spec
        if not g.space.yawed:
            return None
        self.layer.disabled = bool(self.min_yaw.value)
        return None if self.min_yaw.value else round(self.layer.value / (360 / g.yaw_bins)) % g.yaw_bins

    def _level(self) -> int | None:
        """The height level the controls select (r3, r3yaw: the one nearest the height
        slider); None for a ground robot's SOLM."""
        g = self.inputs.solm.grid_spec
        if g.space.ground:
            return None
        return layers.nearest_level(g, float(self.height.value)) if self.height is not None else 0

    def _solm_changed(self, client=None) -> None:
        g = self.inputs.solm.grid_spec
        level, yaw_bin = self._level(), self._yaw_bin()
        with self._busy(client, "drawing the SOLM", self.channel.value):
            if g.space is Space.SE2:
                layer = layers.solm_layer(self.inputs.solm, self.channel.value, yaw_bin)
            else:
                layer = layers.solm_layer(self.inputs.solm, self.channel.value, level, yaw_bin=yaw_bin)
            if g.space.ground:
                points, colors, size = layer["centres"], layer["colors"], layer["res"]
            else:  # a slice through the volume: small squares a cell, which a flight crossing it shows between
                points, colors, size = layers.slice_points(layer)
            self.solm_node = self.server.scene.add_point_cloud(
                "/solm", points, colors, point_size=size, point_shape="square", point_shading="flat"
            )
            self.colorbar.image = layers.colorbar_image(layer["lo"], layer["hi"], layers.CHANNELS[self.channel.value])
        if self.level_text is not None:
            which = ""
            if g.space is Space.R3YAW:
                which = (
                    ", the minimum over yaw"
                    if yaw_bin is None
                    else f", yaw bin {yaw_bin} ({math.degrees(g.yaws()[yaw_bin]):.0f}°)"
                )
            self.level_text.content = (
                f"Level {level + 1} of {len(g.z_levels)}: z = {g.z_levels[level]:.2f} m{which}, "
                f"{len(layer['values']):,} cells shown"
            )

    def _add_given_plans(self) -> None:
        gui = self.server.gui
        if not self.inputs.plans:
            return
        lines, n = [], len(self.inputs.plans)
        for k, (name, samples) in enumerate(self.inputs.plans.items()):
            color = PLAN_COLORS[k % len(PLAN_COLORS)]
            self._draw_trajectory(f"/plans/{k}", samples, color, PLAN_WIDTH + PLAN_STEP * (n - 1 - k), lift=0.02 * k)
            lines.append(
                f"- <span style='color:rgb{color}'>■</span> {name}: "
                f"{layers.path_length(samples['x'], samples['y']):.1f} m, {samples['t'][-1]:.1f} s"
                + self._error_text(*self.predicted_error(samples))
            )
        gui.add_markdown("**Plans**\n\n" + "\n".join(lines))

    def _add_replays(self) -> None:
        if not self.inputs.replays:
            return
        lines = []
        for k, (name, tracks) in enumerate(self.inputs.replays.items()):
            self.server.scene.add_line_segments(
                f"/replays/{k}/truth", tracks["truth"], TRUTH, thickness=TRUTH_WIDTH, thickness_units="screen"
            )
            self.server.scene.add_line_segments(
                f"/replays/{k}/estimate",
                tracks["estimate"],
                tracks["colors"],
                thickness=ESTIMATE_WIDTH,
                thickness_units="screen",
            )
            lines.append(f"- {layers.replay_caption(name, tracks)}")
        self.server.gui.add_markdown("**Replays**\n\n" + "\n".join(lines))

    def _add_flights(self) -> None:
        """Each flight as a tube along its path with the body's axes every FRAME_EVERY_M
        metres (``flight_nodes``: {name: (tube, axes)}), and its figures in the panel."""
        self.flight_nodes = {}
        if not self.inputs.flights:
            return
        solm = self.inputs.solm
        fit = None
        if solm is not None:
            from lf3pm.prediction import solm_fit

            fit = solm_fit(solm)
        lines = []
        for k, (name, samples) in enumerate(self.inputs.flights.items()):
            color = PLAN_COLORS[k % len(PLAN_COLORS)]
            vertices, faces = layers.tube(layers.flight_positions(samples))
            tube = None
            if len(faces):  # a hover has no path to draw a tube along: its axes show it
                tube = self.server.scene.add_mesh_simple(
                    f"/flights/{k}/tube", vertices, faces, color=color, opacity=FLIGHT_OPACITY
                )
            at = layers.frame_samples(samples)
            axes = self.server.scene.add_batched_axes(
                f"/flights/{k}/body",
                samples["wxyz"][at].astype(np.float32),
                layers.flight_positions(samples)[at].astype(np.float32),
                axes_length=AXES_LENGTH,
                axes_radius=AXES_RADIUS,
            )
            self.flight_nodes[name] = (tube, axes)
            summary = layers.flight_summary(samples)
            error = (None, None) if solm is None else layers.flight_predicted_error(solm, samples, fit)
            lines.append(
                f"- <span style='color:rgb{color}'>■</span> {html.escape(name)}: {summary['length_m']:.1f} m, "
                f"{summary['duration_s']:.1f} s, top speed {summary['top_speed_mps']:.1f} m/s, "
                f"largest tilt {summary['largest_tilt_deg']:.0f}°" + self._error_text(*error)
            )
        self.flight_text = self.server.gui.add_markdown(
            "**Flights** (the body's axes every "
            f"{layers.FRAME_EVERY_M:g} m: x red, y green, z blue, the thrust)\n\n" + "\n".join(lines)
        )

    def _set_camera(self) -> None:
        """The first view: from the south and above, on what was given to look at (the
        plans and replays; else the SOLM's grid; else the whole map), a little left of the
        centre, which the panel covers."""
        (x0, y0), (x1, y1) = self.focus_bounds()
        span = max(x1 - x0, y1 - y0, 10.0)
        points = self.inputs.world.points
        inside = (points[:, 0] >= x0) & (points[:, 0] <= x1) & (points[:, 1] >= y0) & (points[:, 1] <= y1)
        ground = float(np.percentile(points[inside, 2], 5)) if inside.any() else float(points[:, 2].min())
        centre = (0.5 * (x0 + x1) + 0.1 * span, 0.5 * (y0 + y1))
        camera = self.server.initial_camera
        camera.look_at = (centre[0], centre[1], ground)
        camera.position = (centre[0], centre[1] - 0.6 * span, ground + 0.6 * span)

    def focus_bounds(self) -> tuple:
        """((xmin, ymin), (xmax, ymax)) of what the first view shows: the given plans,
        flights, replays and recorded run; without them the SOLM's grid, without it the map."""
        xy = [np.c_[s["x"], s["y"]] for s in (*self.inputs.plans.values(), *self.inputs.flights.values())]
        xy += [t["truth"].reshape(-1, 3)[:, :2] for t in self.inputs.replays.values()]
        if self.inputs.run is not None:
            xy.append(self.inputs.run.path_xyz[:, :2])
        solm = self.inputs.solm
        if not xy and solm is not None:
            g = solm.grid_spec
            xy.append(np.reshape(g.bounds, (2, 2)))
        if not xy:
            lo, hi = self.inputs.world.bounds
            return (float(lo[0]), float(lo[1])), (float(hi[0]), float(hi[1]))
        xy = np.concatenate(xy)
        return tuple(map(float, xy.min(axis=0))), tuple(map(float, xy.max(axis=0)))

    # -- a recorded run: its path, its audited scans, a scan over the map -----------------

    def _add_run(self) -> None:
        run = self.inputs.run
        if run is None:
            return
        gui = self.server.gui
        if len(run.path_xyz) > 1:
            self.server.scene.add_line_segments(
                "/run/path", layers.polyline(*run.path_xyz.T), RUN_PATH, thickness=TRUTH_WIDTH, thickness_units="screen"
            )
        choices = len(run.records) if run.records else run.scans
        self.run_quantity = self.run_colorbar = None
        self._shown_scan = None
        self._scan_nodes = []
        with gui.add_folder("Recorded run"):
            where = f"`{html.escape(str(run.path))}`" if run.path is not None else "(not found)"
            audit = ", no audit"
            if run.records:
                audit = f", {len(run.records)} scans audited (`{html.escape(str(run.audit))}`, sensor "
                audit += f"{html.escape(run.sensor)})"
            gui.add_markdown(f"**Run** {where}{audit}: its reference path in white")
            if run.records:
                first = layers.first_known_quantity(run.records)
                self.run_quantity = gui.add_dropdown(
                    "colour scans by", tuple(layers.RUN_QUANTITIES), initial_value=first
                )
                self.run_colorbar = gui.add_image(
                    np.zeros(layers.COLORBAR_PIXELS[::-1] + (3,), np.uint8), label="scans' colour bar"
                )
            self.scan_choice = gui.add_slider(
                "audited scan" if run.records else "scan", min=0, max=max(choices - 1, 0), step=1, initial_value=0
            )
            self.scan_text = gui.add_markdown("")
        if self.run_quantity is not None:
            self.run_quantity.on_update(lambda event: self._guarded(self._draw_scan_markers, event.client))
            self._guarded(self._draw_scan_markers)
        self.scan_choice.on_update(lambda event: self._guarded(self._scan_chosen, event.client))
        self._guarded(self._scan_chosen)  # the first scan, or the line saying why none can be shown

    def _draw_scan_markers(self, client=None) -> None:
        quantity = self.run_quantity.value
        markers = layers.scan_markers(self.inputs.run.records, quantity)
        self._markers = self.server.scene.add_point_cloud(
            "/run/scans",
            markers["positions"],
            markers["colors"],
            point_size=MARKER_SIZE,
            point_shape="circle",
            point_shading="flat",
            precision="float32",
        )
        label = layers.RUN_QUANTITIES[quantity][1]
        if not markers["known"]:
            label = f"{quantity}: not in this audit (every scan grey)"
        self.run_colorbar.image = layers.colorbar_image(markers["lo"], markers["hi"], label, name=layers.RUN_COLORMAP)

    def _scan_clicked(self, event) -> None:
        if not self.inputs.run.records:
            raise Lf3pmError("no audited scans to choose: give --audit, or choose a scan with the slider")
        positions = np.array([r["pose"][:3, 3] for r in self.inputs.run.records])
        chosen = layers.nearest_scan(positions, event.ray_origin, event.ray_direction)
        if chosen is None:
            raise Lf3pmError("no audited scan in front of that click")
        self.show_scan(chosen, event.client)

    def _scan_chosen(self, client=None) -> None:
        # Slider moves queue up while a scan is read: draw the latest one, once.
        if self.scan_choice.value != self._shown_scan:
            self.show_scan(int(self.scan_choice.value), client)

    def show_scan(self, choice: int, client=None) -> dict:
        """Shows scan ``choice``: the audit's ``choice``-th record (without an audit, the
        run's scan ``choice``) in the panel, the scan's real points read from the run and put
        in the world by its reference pose (the audit's), and the simulated scan of the
        audit's sensor at that pose (its seed, noise and scan voxel; without an audit, the
        page's sensor). Returns ``record`` (None without an audit), ``real`` (N, 3) float64
        world points, ``simulated`` (M, 3) float64 hits (None, ``simulated_withheld`` saying
        why, where the pose cannot be simulated)."""
        run = self.inputs.run
        self._shown_scan = None
        for node in self._scan_nodes:  # another scan's points never stay beside this one's record
            node.remove()
        self._scan_nodes = []
        record = run.records[choice] if run.records else None
        index = record["index"] if record is not None else choice
        self.scan_text.content = layers.scan_record_text(record) if record is not None else f"**Scan {index}**"
        with self._busy(client, "reading the run", f"scan {index}"):
            scan = read_scan(run, index)
        pose = record["pose"] if record is not None else scan.pose
        real = layers.world_points(scan.points, pose)
        simulated, withheld = self._simulated_scan(pose)
        self._add_scan_points("real", real, REAL_POINTS)
        sensor = html.escape(str(run.sensor or self.sensor))
        lines = [
            layers.scan_record_text(record) if record is not None else layers.run_scan_text(scan),
            f"- <span style='color:rgb{REAL_POINTS}'>■</span> its {len(real):,} points at its reference pose",
        ]
        if simulated is None:
            lines.append(f"- no simulated scan of {sensor} there: {html.escape(withheld)}")
        else:
            self._add_scan_points("simulated", simulated, SIMULATED_POINTS)
            lines.append(
                f"- <span style='color:rgb{SIMULATED_POINTS}'>■</span> the simulated scan of {sensor} there, "
                f"{len(simulated):,} hits"
            )
        self.scan_text.content = "\n".join(lines)
        self.status = self.scan_text.content
        self._shown_scan = choice
        self.scan_choice.value = choice  # the slider follows a click (its callback sees the scan shown)
        return {"record": record, "real": real, "simulated": simulated, "simulated_withheld": withheld}

    def _add_scan_points(self, name: str, points, color) -> None:
        """Draws a chosen scan's points (float32: a map's coordinates need more than float16)."""
        node = self.server.scene.add_point_cloud(
            f"/run/scan/{name}", points, color, point_size=SCAN_POINT_SIZE, point_shape="circle", precision="float32"
        )
        self._scan_nodes.append(node)

    def _simulated_scan(self, pose: np.ndarray) -> tuple[np.ndarray | None, str | None]:
        """(world hits, None) of the audit's sensor at ``pose`` on the map, as the audit
        simulated it (lf3pm.evaluate, the audit's seed, noise and scan voxel), or (None,
        why) where that pose cannot be simulated (outside the map, too near a point)."""
        import lf3pm

        run = self.inputs.run
        given = {key: run.params[key] for key in ("seed", "noise", "scan_voxel") if run.params.get(key) is not None}
        try:
            result = lf3pm.evaluate(self.inputs.world, pose, run.sensor or self.sensor, observations=True, **given)
        except Lf3pmError as err:
            return None, str(err)
        return np.asarray(result.observations["points"], dtype=np.float64), None

    # -- clicks: inspect a cell, set a start and a goal, plan ------------------------------

    def _add_click_controls(self) -> None:
        gui = self.server.gui
        solm = self.inputs.solm
        planning = solm is not None and solm.grid_spec.space.ground  # lf3pm.Planner plans ground robots
        with gui.add_folder("Click on the ground to"):
            actions = ("inspect a cell", "set the start", "set the goal") if planning else ("inspect a cell",)
            audited = self.inputs.run is not None and bool(self.inputs.run.records)
            self.mode = gui.add_dropdown(
                "action",
                (CHOOSE_SCAN, *actions) if audited else actions,
                initial_value=CHOOSE_SCAN if audited else "inspect a cell",
            )
            self.cell_text = gui.add_markdown(
                "Click a cell: its metric, its simulated scan and its least observable directions."
            )
        if planning:
            with gui.add_folder("Plan"):
                # Or drag the ring that appears at a clicked start or goal.
                self.start_yaw = gui.add_slider("start yaw (deg)", min=-180, max=180, step=5, initial_value=0)
                self.goal_yaw = gui.add_slider("goal yaw (deg)", min=-180, max=180, step=5, initial_value=0)
                button = gui.add_button("plan: default guidance and none")
                self.plan_text = gui.add_markdown(
                    f"Robot: {self.robot.kind} (from the configuration); set a start and a goal by clicking."
                )
            button.on_click(lambda event: self._guarded(self.plan_between, event.client))
            self.start_yaw.on_update(lambda _: self._guarded(self._draw_ends))
            self.goal_yaw.on_update(lambda _: self._guarded(self._draw_ends))
        self.server.scene.on_click()(lambda event: self._guarded(self._clicked, event))

    def _clicked(self, event) -> None:
        if self.mode.value == CHOOSE_SCAN:
            self._scan_clicked(event)
            return
        origin, direction = np.asarray(event.ray_origin), np.asarray(event.ray_direction)
        solm = self.inputs.solm
        aerial = solm is not None and not solm.grid_spec.space.ground
        if aerial:  # the slice shown, not the ground under it
            xy = plane_point(origin, direction, float(solm.grid_spec.z_levels[self._level()]))
        else:
            xy = self.ground_point(origin, direction)
        if xy is None:
            raise Lf3pmError(f"that click does not meet {'the slice shown' if aerial else 'the ground'}")
        if self.mode.value == "inspect a cell":
            self.inspect(xy, event.client)
        elif self.mode.value == "set the start":
            self._start = xy
            self._place_yaw_ring("start", xy)
            self._draw_ends()
        else:
            self._goal = xy
            self._place_yaw_ring("goal", xy)
            self._draw_ends()

    def _yaw_slider(self, end: str):
        return self.start_yaw if end == "start" else self.goal_yaw

    def _place_yaw_ring(self, end: str, xy) -> None:
        """A rotation ring about the vertical at the start or goal: dragging it turns the
        end's heading (and its slider)."""
        yaw = math.radians(self._yaw_slider(end).value)
        ring = self.server.scene.add_transform_controls(
            f"/ends/{end}_yaw",
            scale=2.0,
            active_axes=(False, False, True),
            disable_axes=True,
            disable_sliders=True,
            position=(xy[0], xy[1], self.ground_height(*xy) + self._above_layer),
            wxyz=_yaw_quaternion(yaw),
        )
        ring.on_update(lambda event: self._guarded(self._ring_turned, end, event.target))
        self._rings[end] = ring

    def _ring_turned(self, end: str, ring) -> None:
        degrees = math.degrees(_quaternion_yaw(ring.wxyz))
        slider = self._yaw_slider(end)
        slider.value = float(round(((degrees + 180.0) % 360.0 - 180.0) / slider.step) * slider.step)

    def ground_height(self, x: float, y: float) -> float:
        """The ground under (x, y): the SOLM's ground height there, else the map's lowest
        points nearby."""
        solm = self.inputs.solm
        if solm is not None and solm.grid_spec.space.ground:  # an R3 SOLM stores no ground
            if self._ground is None:
                self._ground = solm.channel("ground_z").astype(np.float64)
            g = solm.grid_spec
            xmin, ymin, xmax, ymax = g.bounds
            inside = xmin <= x < xmax and ymin <= y < ymax
            z = float(self._ground[g.cell(x, y)[-2:]]) if inside else math.nan
            if math.isfinite(z):
                return z
        pts = self.inputs.world.points
        near = pts[np.hypot(pts[:, 0] - x, pts[:, 1] - y) < 1.0]
        return float(np.percentile(near[:, 2], 5)) if len(near) else float(pts[:, 2].min())

    def ground_point(self, origin: np.ndarray, direction: np.ndarray) -> np.ndarray | None:
        """Where a click's ray meets the ground (x, y), or None when it points at the sky."""
        lo, _ = self.inputs.world.bounds
        z = float(lo[2])
        for _ in range(3):  # meet a plane at the ground's height there, then refine
            if direction[2] >= -1e-9:
                return None
            t = (z - origin[2]) / direction[2]
            x, y = origin[:2] + t * direction[:2]
            z = self.ground_height(x, y)
        return np.array([x, y])

    def inspect(self, xy, client=None) -> dict:
        """Evaluates the cell at ``xy``: its SOLM values, lf3pm.evaluate at the SOLM's sensor
        height (r3, r3yaw: the level shown; yaw: the yaw slider, or the cell's best yaw with
        min over yaw; r3yaw: the sensor on the SOLM's mount of the level body), the scan drawn
        as points and the least observable translations as arrows. Returns the evaluation's
        numbers and the body's ``pose`` (x, y, z, yaw)."""
        import lf3pm

        solm = self.inputs.solm
        g = solm.grid_spec if solm is not None else None
        if g is not None and not g.space.ground:
            z = float(g.z_levels[self._level()])  # the level shown, in the map's frame
        else:
            z = self.ground_height(*xy) + (g.height if g is not None else 1.0)
        height = {} if g is None or g.space.ground else {"z": z}
        yaw = 0.0
        if g is not None and g.space.yawed:
            index = self._yaw_bin()
            if index is None:  # the best yaw at this cell
                n = g.yaw_bins
                values = solm.query(
                    np.full(n, xy[0]), np.full(n, xy[1]), yaw=g.yaws(), **{k: np.full(n, v) for k, v in height.items()}
                )[0]
                index = int(np.nanargmin(values)) if np.isfinite(values).any() else 0
            yaw = float(g.yaws()[index])
        pose = (xy[0], xy[1], z, yaw)
        mount = (solm.attrs.get("mount") or {}) if solm is not None else {}
        sensor_pose = np.asarray(pose_matrix(pose)) @ np.asarray(mount.get("matrix", np.eye(4)), dtype=np.float64)
        with self._busy(client, "evaluating", f"cell ({xy[0]:.1f}, {xy[1]:.1f})"):
            result = lf3pm.evaluate(self.inputs.world, sensor_pose, self.sensor, observations=True)
        hits = result.observations["points"].astype(np.float32)
        self.server.scene.add_point_cloud("/cell/scan", hits, SCAN, point_size=0.08, point_shape="circle")
        position = sensor_pose[:3, 3]
        on = f" on its mount {mount['name']}, the body" if mount else ""
        text = [
            (
                f"**Cell** ({xy[0]:.2f}, {xy[1]:.2f}), yaw {math.degrees(yaw):.0f}°, sensor {self.sensor}"
                f"{on} at z = {z:.2f} m"
            ),
            f"- q_min {result.q_min:.4g}, q_n {result.q_n:.4g}, q_max {result.q_max:.4g}",
            f"- {result.hits:,} hits of {result.rays:,} rays (red points)",
        ]
        if result.predicted_localization_error_m is not None:
            lo, hi = result.predicted_localization_error_interval_m
            text.append(
                f"- predicted localization error {result.predicted_localization_error_m * 100:.1f} cm "
                f"({lo * 100:.1f}-{hi * 100:.1f} cm)"
            )
        elif result.predicted_localization_error_withheld is not None:
            text.append(f"- predicted localization error withheld: {result.predicted_localization_error_withheld}")
        if solm is not None:
            stored = float(solm.query(xy[0], xy[1], yaw=yaw, **height)[0])
            text.append(
                f"- SOLM q_n here {stored:.4g} (interpolated)"
                if math.isfinite(stored)
                else "- the SOLM has no value here (an obstacle, unknown ground or its edge)"
            )
        if not result.degenerate and len(result.observations["A"]) >= 6:
            weak = layers.weak_directions(result.observations, position)
            self.server.scene.add_arrows(
                "/cell/weak", weak["arrows"], np.array(ARROWS), shaft_radius=0.05, head_radius=0.15, head_length=0.3
            )
            d = weak["directions"][0]
            text.append(
                f"- least observable translation ({d[0]:+.2f}, {d[1]:+.2f}, {d[2]:+.2f}), red arrow; "
                "orange and yellow: the others, shorter as they are better observed"
            )
        else:
            text.append("- degenerate: the scan does not fix the pose")
        self.cell_text.content = "\n".join(text)
        self.status = self.cell_text.content
        return {"q_n": result.q_n, "hits": result.hits, "pose": pose}

    def _draw_ends(self) -> None:
        for name, xy, yaw_slider, color in (
            ("start", self._start, getattr(self, "start_yaw", None), (60, 220, 60)),
            ("goal", self._goal, getattr(self, "goal_yaw", None), (230, 60, 60)),
        ):
            if xy is None or yaw_slider is None:
                continue
            yaw = math.radians(yaw_slider.value)
            z = self.ground_height(*xy) + self._above_layer
            tip = np.array([xy[0] + 1.5 * math.cos(yaw), xy[1] + 1.5 * math.sin(yaw), z])
            self.server.scene.add_arrows(
                f"/ends/{name}",
                np.array([[[xy[0], xy[1], z], tip]]),
                color,
                shaft_radius=0.08,
                head_radius=0.25,
                head_length=0.5,
            )
            ring = self._rings.get(name)
            # The slider moved: turn the ring with it (a drag keeps within a step).
            if ring is not None and (
                abs(math.remainder(_quaternion_yaw(ring.wxyz) - yaw, 2 * math.pi)) > math.radians(yaw_slider.step)
            ):
                ring.wxyz = _yaw_quaternion(yaw)

    def plan_between(self, client=None) -> dict:
        """Plans from the clicked start to the clicked goal with the default guidance and
        with none (lf3pm.Planner on the SOLM), draws both with the robot's footprint and
        returns {name: summary with the predicted error (:meth:`predicted_error`)}."""
        from lf3pm.planner.plan import Planner

        if self._start is None or self._goal is None:
            raise Lf3pmError("set a start and a goal first (choose the action, then click the ground)")
        start = (*self._start, math.radians(self.start_yaw.value))
        goal = (*self._goal, math.radians(self.goal_yaw.value))
        with self._busy(client, "planning", "default guidance and none"):
            if self._planner is None:
                self._planner = Planner(self.inputs.solm, self.planner_config)
            g = self.guidance
            plans = {
                "default guidance": self._planner.plan(start, goal, robot=self.robot, guidance=g),
                "none (shortest)": self._planner.plan(start, goal, robot=self.robot, metric="none"),
            }
        lines, out = [], {}
        for k, (name, plan) in enumerate(plans.items()):
            samples = plan.trajectory.sample(20.0)
            color = GUIDED if name.startswith("default") else UNGUIDED
            self._draw_trajectory(
                f"/planned/{name.split()[0]}",
                samples,
                color,
                PLAN_WIDTH + PLAN_STEP * (len(plans) - 1 - k),
                lift=0.02 * k,
            )
            summary = plan.summary()
            error, withheld = self.predicted_error(samples)
            out[name] = {**summary, "predicted_error_m": error, "predicted_error_withheld": withheld}
            lines.append(
                f"- <span style='color:rgb{color}'>■</span> {name}: "
                f"{summary['trajectory_length_m']:.1f} m, {summary['duration_s']:.1f} s"
                + self._error_text(error, withheld)
            )
        self.plan_text.content = f"Robot {self.robot.kind}:\n\n" + "\n".join(lines)
        self.status = self.plan_text.content
        return out

    def _draw_trajectory(self, name: str, samples: dict, color, width: float = PLAN_WIDTH, lift: float = 0.0) -> None:
        z = np.array([self.ground_height(x, y) for x, y in zip(samples["x"][::20], samples["y"][::20])])
        z = np.interp(np.arange(len(samples["x"])), np.arange(0, len(samples["x"]), 20), z) + self._above_layer + lift
        path = layers.polyline(samples["x"], samples["y"], z)
        self.server.scene.add_line_segments(f"{name}/path", path, color, thickness=width, thickness_units="screen")
        with_z = dict(samples, z=z)
        self.server.scene.add_line_segments(
            f"{name}/footprint",
            layers.footprints(with_z, self.footprint_radius, FOOTPRINT_EVERY_S),
            color,
            thickness=0.05,
        )

    @staticmethod
    def _error_text(error: float | None, withheld: str | None) -> str:
        if error is not None:
            return f", predicted error {error * 100:.1f} cm"
        return "" if withheld is None else f", predicted error withheld: {html.escape(withheld)}"

    def predicted_error(self, samples: dict) -> tuple[float | None, str | None]:
        """(error, withheld): the localization error (m) predicted along a trajectory's
        samples from the SOLM's q_n (lf3pm.prediction.predicted_error_along, with the SOLM's
        fit); or None and why, in one line. (None, None) without a SOLM or a fit."""
        from lf3pm.prediction import predicted_error_along, solm_fit

        solm = self.inputs.solm
        fit = None if solm is None else solm_fit(solm)
        if fit is None:
            return None, None
        return predicted_error_along(solm, samples, fit)

    # -- progress, errors and shutdown ---------------------------------------------------

    @contextmanager
    def _busy(self, client, title: str, body: str = ""):
        """A notice in the page of ``client`` (None: none) while the block runs."""
        note = client.add_notification(title, body, loading=True, with_close_button=False) if client else None
        try:
            yield
        finally:
            if note is not None:
                note.remove()

    def _guarded(self, action, *args):
        """Runs a page action; an error becomes a message in the page (and in ``status``).
        A fault of the storage or the SOLM, or an unexpected error, is also one line on
        stderr: the page keeps serving what it can."""
        name = getattr(action, "__name__", repr(action))
        with self._lock:
            try:
                result = action(*args)
            except (StorageError, CorruptStoreError) as err:
                self._show_error(name, str(err), args)
                print(f"lf3pm view: error: {err}", file=sys.stderr)
            except Lf3pmError as err:
                self._show_error(name, str(err), args)
            except Exception as err:  # noqa: BLE001 - a page action must never kill the page
                message = f"{err.__class__.__name__}: {err}"
                self._show_error(name, message, args)
                print(f"lf3pm view: {message}", file=sys.stderr)
            else:
                if self._errors.pop(name, None) is not None:
                    self._show_errors()
                return result

    def _show_error(self, action: str, message: str, args) -> None:
        self.status = f"error: {message}"
        self._errors[action] = message
        self._show_errors()
        client = next((a for a in args if hasattr(a, "add_notification")), None)
        client = client or next((getattr(a, "client", None) for a in args if hasattr(a, "client")), None)
        targets = [client] if client is not None else list(self.server.get_clients().values())
        for c in targets:
            c.add_notification("lf3pm", message, color="red", auto_close_seconds=10.0)

    def _show_errors(self) -> None:
        """The errors of the actions that failed last, in the panel for every page open now
        or later, verbatim (a path may hold markup)."""
        self.error_text.content = "".join(
            f"<div style='color:#c62828;font-size:0.85em;overflow-wrap:anywhere'><b>error:</b> {html.escape(m)}</div>"
            for m in self._errors.values()
        )
        self.error_text.visible = bool(self._errors)

    def stop(self) -> None:
        self.server.stop()


def plane_point(origin: np.ndarray, direction: np.ndarray, z: float) -> np.ndarray | None:
    """Where a click's ray meets the horizontal plane at height ``z`` (x, y), or None when
    it does not (parallel to it, or pointing away)."""
    if abs(direction[2]) < 1e-12:
        return None
    t = (z - origin[2]) / direction[2]
    return None if t <= 0 else np.asarray(origin[:2] + t * direction[:2], dtype=np.float64)


def _yaw_quaternion(yaw: float) -> tuple:
    """(w, x, y, z) of a rotation by ``yaw`` about the vertical."""
    return (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))


def _quaternion_yaw(wxyz) -> float:
    """The yaw of a rotation about the vertical given as (w, x, y, z)."""
    return 2.0 * math.atan2(wxyz[3], wxyz[0])


def serve(
    inputs: ViewInputs,
    *,
    host: str = DEFAULT_HOST,
    port: int = DEFAULT_PORT,
    robot=None,
    guidance: GuidanceConfig | None = None,
    sensor: str | None = None,
    planner: PlannerConfig | None = None,
    z: float | None = None,
) -> ViewApp:
    """Starts the viewer of ``inputs`` (lf3pm.view.load_view_inputs) on ``host``:``port``
    and returns it (its server runs in a thread; ``stop()`` ends it). ``port`` 0 serves on
    any free port (``ViewApp.port`` says which); any other port must be free: one in use
    is an Lf3pmError, never another port silently. ``host`` and ``port`` are checked as
    ``lf3pm view`` checks them (check_host, check_port). ``robot``, ``guidance`` and the
    ``planner`` section plan the clicked start and goal (default: the configuration's); ``sensor`` evaluates
    clicked cells (default: the SOLM's). ``z``: the height (m) of the r3 or r3yaw SOLM's
    slice shown first, its nearest level (default the lowest); one outside the SOLM's
    levels, or without such a SOLM, is an Lf3pmError."""
    from lf3pm.sensors import as_sensor
    from lf3pm.trajectory.robots import Robot

    if not isinstance(inputs, ViewInputs):
        raise Lf3pmError(f"serve needs the viewer's inputs (lf3pm.view.load_view_inputs), got {type(inputs).__name__}")
    if isinstance(port, int) and not isinstance(port, bool) and port == 0:
        check_host(host)
    else:
        check_port(host, port)
    if robot is not None and not isinstance(robot, Robot):
        raise Lf3pmError(f"robot must be an lf3pm.Robot, got {type(robot).__name__}")
    if guidance is not None and not isinstance(guidance, GuidanceConfig):
        raise Lf3pmError(f"guidance must be an lf3pm.config.GuidanceConfig, got {type(guidance).__name__}")
    if planner is not None and not isinstance(planner, PlannerConfig):
        raise Lf3pmError(f"planner must be an lf3pm.config.PlannerConfig, got {type(planner).__name__}")
    if sensor is not None:
        as_sensor(sensor)  # an unknown sensor fails here, not at the first click
    if z is not None:
        if inputs.solm is None:
            raise Lf3pmError("a height picks a level of an r3 or r3yaw SOLM: give one (--solm)")
        layers.nearest_level(inputs.solm.grid_spec, z)
    return ViewApp(
        inputs, host=host, port=int(port), robot=robot, guidance=guidance, sensor=sensor, planner=planner, z=z
    )
