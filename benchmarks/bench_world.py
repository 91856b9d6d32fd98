"""Speed of the navigation domain: sensor scans, env.step, world sampling.

Goals (issue: foundation and navigation world), all per item, medians:
- a 32-ray scan in a 12-gon with 15 discs: <= 10 µs single, <= 3 µs batched over >= 100
  agents; reported as a ratio against the Shapely 2 reference in the same run;
- env.step >= 20,000 steps/s (<= 50 µs);
- sampling a world <= 1 ms.
"""

from __future__ import annotations

import numpy as np

from benchmarks._timing import Timing, median_time, note, report
from copi.envs.navigation import NavigationEnv
from copi.geometry import cast_rays
from copi.geometry.kernels import scan
from copi.geometry.reference import cast_rays_numpy, cast_rays_shapely
from copi.world import RangeSensor, WorldParams, random_world, sample_start_goal


def scene() -> tuple:
    world = random_world(0, params=WorldParams(sides=(12, 12)))
    rng = np.random.default_rng(1)
    xmin, ymin, xmax, ymax = world.bounds
    pts = rng.uniform([xmin, ymin], [xmax, ymax], size=(4000, 2))
    pts = pts[world.contains(pts) & (world.clearance(pts) > 0.3)]
    centers = pts[:15]
    radii = rng.uniform(0.5, 1.0, 15)
    agents = pts[15:]
    return world, centers, radii, agents


def bench_scan() -> bool:
    world, centers, radii, agents = scene()
    sensor = RangeSensor()
    ang, segs = sensor.angles, np.ascontiguousarray(world.segments)
    o = agents[0]
    batch = np.ascontiguousarray(agents[:1000])
    out1 = np.empty((1, 32))
    outb = np.empty((len(batch), 32))
    rows = [
        Timing(
            "shapely 2 (single)",
            median_time(lambda: cast_rays_shapely(o, ang, segs, centers, radii), number=50),
        ),
        Timing(
            "numpy (single)",
            median_time(lambda: cast_rays_numpy(o, ang, segs, centers, radii), number=500),
        ),
        Timing(
            "numpy (batch of 100)",
            median_time(lambda: cast_rays_numpy(batch[:100], ang, segs, centers, radii), number=50),
            per=100,
        ),
        Timing(
            "copi cast_rays (single)",
            median_time(lambda: cast_rays(o, ang, segs, centers, radii), number=5000),
        ),
        Timing(
            "copi RangeSensor.scan (single)",
            median_time(lambda: sensor.scan(world, o, centers, radii), number=5000),
        ),
        Timing(
            "copi kernel (single)",
            median_time(
                lambda: scan(o[None], sensor.cos, sensor.sin, segs, centers, radii, 10.0, out1),
                number=20000,
            ),
        ),
        Timing(
            "copi cast_rays (batch of 100)",
            median_time(lambda: cast_rays(batch[:100], ang, segs, centers, radii), number=500),
            per=100,
        ),
        Timing(
            f"copi cast_rays (batch of {len(batch)})",
            median_time(lambda: cast_rays(batch, ang, segs, centers, radii), number=50),
            per=len(batch),
        ),
        Timing(
            f"copi kernel (batch of {len(batch)})",
            median_time(
                lambda: scan(batch, sensor.cos, sensor.sin, segs, centers, radii, 10.0, outb),
                number=50,
            ),
            per=len(batch),
        ),
    ]
    return report(
        "32-ray scan, 12-gon + 15 discs (per scan)",
        rows,
        "shapely 2 (single)",
        {
            "copi cast_rays (single)": 10e-6,
            "copi cast_rays (batch of 100)": 3e-6,
        },
    )


def bench_step_and_sampling() -> bool:
    env = NavigationEnv()
    env.reset(seed=0)
    action = np.array([0.6, 0.3], dtype=np.float32)

    def step() -> None:
        _, _, term, trunc, _ = env.step(action)
        if term or trunc:
            env.reset()

    import gymnasium

    wrapped = gymnasium.make("copi/Navigation-v0")
    wrapped.reset(seed=0)

    def wrapped_step() -> None:
        _, _, term, trunc, _ = wrapped.step(action)
        if term or trunc:
            wrapped.reset()

    rng = np.random.default_rng(0)

    def sample_task() -> None:
        w = random_world(rng)
        sample_start_goal(w, rng)

    rows = [
        Timing("env.step (NavigationEnv)", median_time(step, number=5000)),
        Timing("env.step (gymnasium.make, wrapped)", median_time(wrapped_step, number=5000)),
        Timing("random_world", median_time(lambda: random_world(rng), number=500)),
        Timing("random_world + start/goal", median_time(sample_task, number=300)),
        Timing("env.reset (world + task + obstacles)", median_time(env.reset, number=200)),
    ]
    ok = report(
        "navigation domain",
        rows,
        None,
        {"env.step (NavigationEnv)": 50e-6, "random_world": 1e-3},
    )
    note(f"env.step: {1 / rows[0].seconds:,.0f} steps/s (goal >= 20,000)")
    return ok


def main() -> bool:
    return bench_scan() & bench_step_and_sampling()


if __name__ == "__main__":
    raise SystemExit(0 if main() else 1)
