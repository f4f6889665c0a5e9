"""Trial data: motion-capture trials, force platforms, stance windows and blade kinematics."""

from bladelab.trial.stance import STANCE_COLUMNS, Stance, read_stance_csv, write_stance_csv

__all__ = ["STANCE_COLUMNS", "Stance", "read_stance_csv", "write_stance_csv"]
