"""The shared 3D scene's fixed part: theme, camera, legend, surface grid, compass, depth scale
and the vehicle model (hidden until the first pose). Display only: no callbacks."""

from __future__ import annotations

from typing import Final

import numpy as np
import viser

from backend.viewer.draw import (
    EAST_RGB,
    HULL_RGB,
    NORTH_RGB,
    NOSE_RGB,
    SCALE_RGB,
    Canvas,
    FloatArray,
    ned_to_view,
)

#: Vehicle hull size (m): length, beam, height.
HULL_M: Final = (0.6, 0.3, 0.25)
#: The vehicle's label, above the vehicle (m, view frame).
VEHICLE_LABEL_UP_M: Final = 0.45
#: Depth scale below the origin: length and label spacing (m).
DEPTH_SCALE_M: Final = 20.0
DEPTH_TICK_M: Final = 5.0

LEGEND: Final = (
    "**NemeSys console** (display only)  \n"
    "orange: join, cyan: pattern (preview)  \n"
    "green: active path, yellow: track  \n"
    "magenta: replay, red: commands  \n"
    "violet: mission script  \n"
    "red ring: believed position, no fresh fix  \n"
    "grid: surface, 1 m cells, 10 m sections"
)


def setup_scene(server: viser.ViserServer, canvas: Canvas) -> dict[str, tuple[float, float, float]]:
    """Draw the fixed scene on ``canvas`` (the shared scene); returns its labels' anchors by
    node name (view frame, m)."""
    labels: dict[str, tuple[float, float, float]] = {}
    scene, add = server.scene, canvas.add

    def label(name: str, text: str, position: FloatArray, anchor: str, scale: float) -> None:
        p = (float(position[0]), float(position[1]), float(position[2]))
        labels[name] = p
        add(
            scene.add_label(
                name,
                text,
                position=p,
                anchor=anchor,  # type: ignore[arg-type]
                font_screen_scale=scale,
            )
        )

    server.gui.configure_theme(
        dark_mode=True, show_logo=False, show_share_button=False, control_width="small"
    )
    scene.set_up_direction("+z")
    # above and behind (south of) the origin, looking north-down at it; ~25 m away
    server.initial_camera.position = (0.0, -18.0, 17.0)
    server.initial_camera.look_at = (0.0, 0.0, 0.0)
    server.gui.add_markdown(LEGEND)
    # a small legend in the bottom-right corner, minimised: on a laptop's screen the open
    # panel would cover a third of the view (one click opens it)
    server.gui.main_panel.float(x=-10, y=-10, width=260, height=190)
    server.gui.main_panel.minimize()
    with server.atomic():
        add(
            scene.add_grid(
                "/surface/grid",
                width=200.0,
                height=200.0,
                plane="xy",
                cell_size=1.0,
                section_size=10.0,
                cell_color=(70, 75, 90),
                section_color=(120, 130, 150),
                infinite_grid=True,
                fade_distance=200.0,
                plane_color=(30, 80, 130),
                plane_opacity=0.08,
                shadow_opacity=0.0,
            )
        )
        axes = ned_to_view([0.0, 10.0, 0.0, 0.0], [0.0, 0.0, 0.0, 10.0], [0.0] * 4)
        colors = np.array([[NORTH_RGB] * 2, [EAST_RGB] * 2], dtype=np.uint8)
        add(
            scene.add_line_segments(
                "/scale/axes",
                axes.reshape(2, 2, 3),
                colors,
                thickness=2.0,
                thickness_units="screen",
            )
        )
        label("/scale/north", "N", ned_to_view(11.0, 0.0, 0.0), "center-center", 1.0)
        label("/scale/east", "E", ned_to_view(0.0, 11.0, 0.0), "center-center", 1.0)
        ticks = [ned_to_view([0.0, 0.0], [0.0, 0.0], [0.0, DEPTH_SCALE_M])]
        for d in np.arange(DEPTH_TICK_M, DEPTH_SCALE_M + 1e-9, DEPTH_TICK_M):
            ticks.append(ned_to_view([0.0, 0.0], [-0.5, 0.5], [d, d]))
            label(
                f"/scale/depth_{int(d):02d}m",
                f"{d:g} m",
                ned_to_view(0.0, 0.6, d),
                "center-left",
                0.8,
            )
        add(
            scene.add_line_segments(
                "/scale/depth",
                np.stack(ticks),
                SCALE_RGB,
                thickness=1.5,
                thickness_units="screen",
            )
        )
        add(scene.add_frame("/vehicle", show_axes=False, visible=False))
        add(
            scene.add_box(
                "/vehicle/hull", HULL_RGB, HULL_M, cast_shadow=False, receive_shadow=False
            )
        )
        nose = np.array([[[HULL_M[0] / 2, 0.0, 0.0], [HULL_M[0] / 2 + 0.5, 0.0, 0.0]]])
        add(
            scene.add_arrows(
                "/vehicle/nose",
                nose,
                NOSE_RGB,
                shaft_radius=0.025,
                head_radius=0.06,
                head_length=0.15,
            )
        )
        add(
            scene.add_label(
                "/vehicle/info",
                "",
                position=(0.0, 0.0, VEHICLE_LABEL_UP_M),
                anchor="bottom-center",
                font_screen_scale=0.8,
            )
        )
    return labels
