"""The real robot: identify the model from measured records and judge it on held-out real motion.

Records in (:mod:`~pendulab.identify.records`), prepared (:mod:`~pendulab.identify.preprocess`),
fitted by a physically consistent regression on the symbolic inverse dynamics
(:mod:`~pendulab.identify.regressor`, :mod:`~pendulab.identify.fit`), refined on the measured angles
by multiple shooting (:mod:`~pendulab.identify.output_error`), the structure chosen by held-out
error (:mod:`~pendulab.identify.pipeline`), written as a plant file
(:mod:`~pendulab.model.plant_file`) and judged leave-one-record-out beside published sets
(:mod:`~pendulab.identify.validation`). See ``docs/identification.md``.
"""

from ..model.plant_file import IdentifiedPlant, load_plant, save_plant
from .pipeline import STRUCTURES, Identification, identify
from .records import REALAIGYM_COLUMNS, ColumnMap, Record, RecordError, read_record

__all__ = [
    "identify",
    "Identification",
    "STRUCTURES",
    "IdentifiedPlant",
    "load_plant",
    "save_plant",
    "read_record",
    "Record",
    "RecordError",
    "ColumnMap",
    "REALAIGYM_COLUMNS",
]
