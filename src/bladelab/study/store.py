"""``results.sqlite``: one row per trial × model variant.

The table ``results`` has the unique key (``trial_id``, ``variant``): two runs never write the same
row twice (without ``force`` a second insert of a finished row is ignored). The database runs in WAL
mode and every finished task is committed on its own, so killing a run loses nothing that
finished. Parameters carry their unit in the column name (N·m/deg, N·m·s/deg). The quality columns
(``converged``, ``at_bound``, CI half-widths, peak forces, ``flagged``, ``flags``: see
:mod:`bladelab.identify.quality`) are added to a database written before they existed (NULL in
its old rows).
"""

from __future__ import annotations

import json
import os
import socket
import sqlite3
from collections.abc import Iterable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pandas as pd

from bladelab._io import atomic_open
from bladelab.errors import InputFileError
from bladelab.identify.quality import QUALITY_COLUMNS

COLUMNS: dict[str, str] = {
    "trial_id": "TEXT NOT NULL",
    "variant": "TEXT NOT NULL",
    "status": "TEXT NOT NULL",  # "ok" or "failed"
    "athlete": "TEXT",
    "blade": "TEXT",
    "category": "TEXT",
    "configuration": "TEXT",
    "speed_pct_pb": "REAL",
    "K_Nm_per_deg": "REAL",
    "D_Nms_per_deg": "REAL",
    "K2_Nm_per_deg2": "REAL",
    "K_ci_low_Nm_per_deg": "REAL",
    "K_ci_high_Nm_per_deg": "REAL",
    "D_ci_low_Nms_per_deg": "REAL",
    "D_ci_high_Nms_per_deg": "REAL",
    "KD_correlation": "REAL",
    "poorly_determined": "TEXT",
    "nrmse_grf_pct": "REAL",
    "nrmse_distance_pct": "REAL",
    "cost": "REAL",
    "aic": "REAL",
    "bic": "REAL",
    **QUALITY_COLUMNS,
    "evaluations": "INTEGER",
    "wall_s": "REAL",
    "error": "TEXT",
    "settings_json": "TEXT",
    "seed": "INTEGER",
    "package_version": "TEXT",
    "input_hash": "TEXT",
    "finished_utc": "TEXT",
}


class ResultsStore:
    """The results database of a study folder (created on first use).

    Parameters
    ----------
    path
        Path of ``results.sqlite``.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        try:
            self._con = sqlite3.connect(self.path, timeout=30.0)
            self._con.execute("PRAGMA journal_mode=WAL")
            self._con.execute("PRAGMA synchronous=NORMAL")
            cols = ", ".join(f'"{k}" {v}' for k, v in COLUMNS.items())
            self._con.execute(
                f"CREATE TABLE IF NOT EXISTS results ({cols}, PRIMARY KEY (trial_id, variant))"
            )
            # a database written by an older version lacks the newer columns (NULL there)
            have = {r[1] for r in self._con.execute("PRAGMA table_info(results)")}
            for name, kind in COLUMNS.items():
                if name not in have:
                    self._con.execute(f'ALTER TABLE results ADD COLUMN "{name}" {kind}')
            self._con.execute(
                "CREATE TABLE IF NOT EXISTS claims (trial_id TEXT, variant TEXT, owner TEXT, "
                "host TEXT, pid INTEGER, claimed_utc TEXT, PRIMARY KEY (trial_id, variant))"
            )
            self._con.commit()
        except sqlite3.DatabaseError as err:
            raise InputFileError(f"not a results database ({err})", file=self.path,
                                 hint="move the file away; it will be recreated") from None

    def close(self) -> None:
        """Close the connection."""
        self._con.close()

    def __enter__(self) -> ResultsStore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def done(self, trial_id: str, variant: str, input_hash: str | None = None) -> bool:
        """True if a successful row exists for (trial, variant) (and the same input hash, if given)."""
        row = self._con.execute(
            "SELECT input_hash FROM results WHERE trial_id=? AND variant=? AND status='ok'",
            (trial_id, variant),
        ).fetchone()
        return row is not None and (input_hash is None or row[0] == input_hash)

    def write(self, row: dict[str, Any], *, force: bool = False) -> bool:
        """Insert one row and commit it; returns False if it already existed and was kept.

        A failed row is replaced by any later result; a successful row only with ``force`` or by a
        successful result from changed inputs (another input hash).
        """
        row = dict(row)
        row.setdefault("finished_utc", datetime.now(UTC).isoformat(timespec="seconds"))
        if isinstance(row.get("settings_json"), dict):
            row["settings_json"] = json.dumps(row["settings_json"], sort_keys=True)
        unknown = set(row) - set(COLUMNS)
        if unknown:
            raise KeyError(f"unknown result column(s): {', '.join(sorted(unknown))}")
        keys = list(row)
        sql_cols = ", ".join(f'"{k}"' for k in keys)
        marks = ", ".join("?" for _ in keys)
        values = [row[k] for k in keys]
        with self._con:  # one transaction per finished task
            if force:
                cur = self._con.execute(f"INSERT OR REPLACE INTO results ({sql_cols}) VALUES ({marks})", values)
                return cur.rowcount > 0
            updates = ", ".join(f'"{k}"=excluded."{k}"' for k in keys if k not in ("trial_id", "variant"))
            cur = self._con.execute(
                f"INSERT INTO results ({sql_cols}) VALUES ({marks}) "
                f"ON CONFLICT(trial_id, variant) DO UPDATE SET {updates} "
                "WHERE results.status != 'ok' OR (excluded.status = 'ok' "
                "AND results.input_hash IS NOT excluded.input_hash)",
                values,
            )
            return cur.rowcount > 0

    def claim(self, keys: Iterable[tuple[str, str]], owner: str) -> list[tuple[str, str]]:
        """Claim (trial, variant) tasks for the run ``owner``, in one transaction; returns the
        ones claimed. A task claimed by another run whose process is still alive (same host) or
        that is not on this host is left to it; a claim of a dead process is taken over."""
        host, pid = socket.gethostname(), os.getpid()
        now = datetime.now(UTC).isoformat(timespec="seconds")
        got = []
        with self._con:
            self._con.execute("BEGIN IMMEDIATE")
            for trial_id, variant in keys:
                row = self._con.execute(
                    "SELECT owner, host, pid FROM claims WHERE trial_id=? AND variant=?",
                    (trial_id, variant),
                ).fetchone()
                if row is not None and row[0] != owner and not _dead(row[1], row[2]):
                    continue
                self._con.execute(
                    "INSERT OR REPLACE INTO claims VALUES (?, ?, ?, ?, ?, ?)",
                    (trial_id, variant, owner, host, pid, now),
                )
                got.append((trial_id, variant))
        return got

    def release(self, owner: str) -> None:
        """Drop every claim of the run ``owner`` (its tasks are finished or abandoned)."""
        with self._con:
            self._con.execute("DELETE FROM claims WHERE owner=?", (owner,))

    def table(self, *, status: Iterable[str] | None = None) -> pd.DataFrame:
        """All rows as a DataFrame (optionally only some statuses), ordered by trial and variant."""
        df = pd.read_sql_query("SELECT * FROM results ORDER BY trial_id, variant", self._con)
        if status is not None:
            df = df[df["status"].isin(list(status))].reset_index(drop=True)
        return df


def _dead(host: str, pid: int) -> bool:
    """True when the claiming process ran on this host and is gone."""
    if host != socket.gethostname():
        return False
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return True
    except OSError:  # exists, owned by someone else
        return False
    return False


def open_results(study_dir: str | Path) -> pd.DataFrame:
    """The results table of a study folder (raises if there is none yet)."""
    path = Path(study_dir) / "results.sqlite"
    if not path.is_file():
        raise InputFileError("no results.sqlite yet", file=path,
                             hint=f"run `bladelab identify {study_dir} --blade ...` first")
    with ResultsStore(path) as store:
        return store.table()


def export_results_csv(study_dir: str | Path, path: str | Path) -> int:
    """Write a study's results table (every column, units in the names) as CSV to ``path``,
    atomically; returns the number of rows."""
    df = open_results(study_dir)
    with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
        df.to_csv(fh, index=False)
    return len(df)
