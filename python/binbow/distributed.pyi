from os import PathLike
from typing import Iterable, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

from . import BowVector, Vocabulary

_StrPath = Union[str, PathLike[str]]
_Image = Union[BowVector, npt.NDArray[np.uint8], None]

DEFAULT_TIMEOUT: float

class ShardedDatabase:
    workers: list[str]
    def __init__(
        self,
        client: object,
        vocabulary: Vocabulary,
        shards: int = 1,
        timeout: float = ...,
        *,
        direct_index: bool = True,
        levels_up: int = 4,
    ) -> None: ...
    def add(self, image: _Image, label: Optional[str] = None) -> int: ...
    def add_many(
        self, images: Iterable[_Image], labels: Optional[Sequence[Optional[str]]] = None
    ) -> list[int]: ...
    def transform(self, image: _Image) -> BowVector: ...
    def query(
        self,
        image: _Image,
        max_results: int = 10,
        max_entry_id: Optional[int] = None,
        fast: bool = False,
        *,
        fast_candidates: Optional[int] = None,
        fast_candidate_share: Optional[float] = None,
        fast_min_postings: Optional[int] = None,
    ) -> list[tuple[int, float, int]]: ...
    def remove(self, entry: int) -> None: ...
    def label(self, entry: int) -> Optional[str]: ...
    def set_label(self, entry: int, label: str) -> None: ...
    def __contains__(self, entry: int) -> bool: ...
    def __len__(self) -> int: ...
    @property
    def next_entry_id(self) -> int: ...
    @property
    def shards(self) -> int: ...
    @property
    def vocabulary(self) -> Vocabulary: ...
    def save(self, folder: _StrPath) -> None: ...
    def save_incremental(self, folder: _StrPath) -> None: ...
    @classmethod
    def load(
        cls, client: object, folder: _StrPath, vocabulary: Vocabulary, timeout: float = ...
    ) -> ShardedDatabase: ...
