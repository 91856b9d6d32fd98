"""A new task for the second peer: the homicidal chauffeur's evader (docs/rl.md's section).

    python studies/rl_new_task.py --bench results/rl-game --games 200

The game hands its evader a local reading and the game's direction, no map (level
sensor). The second peer's policies trained at that level (``ppo-F-sensor``: navigation
in family F, the reading stacked with its own velocity) play it unchanged, under the
game's direction, beside copi-learnt with its capabilities unchanged (learnt once,
without any task), compass-guard, the first peer's policy trained for the game
(``ppo-chauffeur``) and the game's direction itself: the same games (seed 0), paired.
The games go into ``--bench/games.sqlite`` (resumable); the section is written into
``--out`` in place of its last version (after the first peer's new task, where there is
none).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from copi.experiments import PursuitConfig, ensure_capabilities, pursue  # noqa: E402
from copi.methods import method_names, method_spec  # noqa: E402
from copi.results import ResultsStore, paired_difference  # noqa: E402
from studies._common import splice_section  # noqa: E402

FIGURE = "rl-curve-chauffeur-sensor.png"
"""The learning curve of the second peer trained for the game (validation survival)."""
SECTION = "## A new task for the second peer: the chauffeur's evader (level sensor)"
AFTER = "## A new task: the homicidal chauffeur's evader"
PEERS = tuple(m for m in ("ppo-star-sensor", "ppo-crowd-sensor", "ppo-chauffeur-sensor")
              if m in method_names() and method_spec(m).available())  # fmt: skip
"""The second peer's policies at level sensor (the game's), where they were trained: for
navigation, and for the game itself."""
NAMES = {"learnt": "copi-learnt (capabilities unchanged; compass-guard's guard as a filter)",
         "compass-guard": "compass-guard (hand-written)",
         "ppo-star-sensor": "ppo-star-sensor (second peer, navigation in star; nothing "
                            "hand-written)",
         "ppo-crowd-sensor": "ppo-crowd-sensor (second peer, navigation in crowds; nothing "
                             "hand-written)",
         "ppo-chauffeur-sensor": "ppo-chauffeur-sensor (second peer, trained for the game; "
                                 "nothing hand-written)",
         "ppo-chauffeur": "ppo-chauffeur (first peer, trained for the game)",
         "game": "the game's direction itself (no avoidance)"}  # fmt: skip


def survived(store: Path, config: PursuitConfig) -> dict[int, bool]:
    """Whether the evader escaped, game by game (played into ``store`` once)."""
    run = pursue(config, store)
    with ResultsStore(store, readonly=True) as s:
        rows = s.games(run)
    return {int(r.game): r.outcome == "escaped" for r in rows if r.game < config.games}


def lines(bench: Path, games: int) -> list[str]:
    bench.mkdir(parents=True, exist_ok=True)
    caps = ensure_capabilities(bench, {"learnt"})["learnt"]
    store = bench / "games.sqlite"
    evaders = ["learnt", "compass-guard", *PEERS, "ppo-chauffeur", "game"]
    won = {}
    for e in evaders:
        config = PursuitConfig(capabilities=None if e == "game" else str(caps), evader=e,
                               games=games, seed=0)  # fmt: skip
        won[e] = survived(store, config)
    rate = {e: float(np.mean(list(won[e].values()))) for e in evaders}
    rows = []
    for e in evaders:
        if e == "learnt":
            rows.append(f"| {NAMES[e]} | {100 * rate[e]:.1f} % | — |  |")
            continue
        common = sorted(set(won["learnt"]) & set(won[e]))
        d = paired_difference([won["learnt"][k] for k in common], [won[e][k] for k in common])
        who = ("neither (interval holds 0)" if not d.excludes_zero
               else "**copi-learnt**" if d.estimate > 0 else f"**{e}**")  # fmt: skip
        rows.append(f"| {NAMES[e]} | {100 * rate[e]:.1f} % | {100 * d.estimate:+.1f} "
                    f"[{100 * d.low:+.1f}, {100 * d.high:+.1f}] | {who} |")  # fmt: skip
    best = max(PEERS, key=lambda e: rate[e], default=None)
    game_peer = "ppo-chauffeur-sensor" in PEERS
    return [
        SECTION,
        "",
        f"`python studies/rl_new_task.py --bench {bench} --games {games}`. The game "
        "gives its evader a local reading and the game's direction, no map: level sensor, "
        "where the second peer was trained as `ppo-F-sensor` (the reading, three stacked, "
        "its own velocity, the goal's direction), played here unchanged under the game's "
        "direction as copi-learnt is with its capabilities learnt once without any task"
        + (", and as `ppo-chauffeur-sensor`, the same observation trained for the game "
           "itself (`python studies/rl_train_all.py --only chauffeur-sensor --seeds 0`: copi "
           "rl train's defaults, 2M steps, survival rewarded, a capture or contact "
           "penalised)" if game_peer else "")
        + f". {games} games of seed 0, the same games for every evader, paired with "
        "copi-learnt.",
        "",
        "| evader | survival | Δ copi-learnt − it | better |",
        "|---|---|---|---|",
        *rows,
        "",
        (f"The second peer's best here, {best}, survives {100 * rate[best]:.1f} %, against "
         f"{100 * rate['game']:.1f} % for the game's direction with no avoidance. copi-learnt's "
         f"lead is its guard's: compass-guard alone survives {100 * rate['compass-guard']:.1f} "
         "%, and no copi method without the guard plays the game (copi-predictive needs the "
         "map)." if best else "No second-peer policy at level sensor is shipped."),
        "",
        *([f"![ppo-chauffeur-sensor]({FIGURE})", ""] if game_peer
          and (Path(__file__).resolve().parents[1] / "docs" / FIGURE).is_file() else []),
    ]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bench", default="results/rl-game")
    ap.add_argument("--games", type=int, default=200)
    ap.add_argument("--out", default="docs/rl.md")
    a = ap.parse_args()
    section = lines(Path(a.bench), a.games)
    splice_section(Path(a.out), SECTION, section, after=AFTER)
    print("\n".join(section))
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
