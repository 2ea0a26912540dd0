"""A binbow.Database split into shards held by the workers of a Dask cluster.

ShardedDatabase gives the answers of one binbow.Database (same dense ids,
same query results to the last bit, ties included) while the entries live on
many machines. Entry `id` lives on shard `id % shards` under the shard's own
id `id // shards`: every shard receives its entries in increasing global id
order and never reuses an id, so the mapping is arithmetic and needs no table.

Dask is imported when a ShardedDatabase is made, so `import binbow` works
without it. See docs/distributed.md.
"""

import errno
import fcntl
import json
import math
import os
import re
import secrets

import numpy as _np

from . import BowVector, Database, Error, Vocabulary
from ._binbow import (_check_bow, _check_query_options, _checked_descriptors, _count_argument,
                      _label_argument)

__all__ = ["ShardedDatabase"]

# Seconds a call to a shard may take before the client gives up (adding or
# saving a large batch takes longest); ShardedDatabase(timeout=...) changes it.
DEFAULT_TIMEOUT = 120.0

_MANIFEST = "manifest.json"
_FORMAT = "binbow-sharded-database"
_FORMAT_VERSION = 1


def _distributed():
    try:
        import distributed
    except ImportError as error:
        raise ImportError(
            f"binbow.distributed needs Dask distributed ({error}): install Debian's "
            "python3-distributed (scripts/install-deps.sh)") from error
    return distributed


class _Shard:
    """The Dask actor holding one shard's binbow.Database on a worker."""

    def __init__(self, vocabulary, options, path=None):
        if path is None:
            self.database = Database(vocabulary, **options)
        else:
            self.database = Database.load(path, vocabulary)

    def add_many(self, items):
        """Adds (descriptors or BowVector, label) pairs; (their shard ids, None or the error)."""
        ids = []
        try:
            for item, label in items:
                if isinstance(item, BowVector):
                    ids.append(self.database.add_bow(item, label))
                else:
                    ids.append(self.database.add(item, label))
        except Exception as error:  # reported with how far the batch got
            return ids, error
        return ids, None

    def append_journal(self, path):
        """(whether the changes went to the journal of `path`, the journal's bytes).

        The size is read here, by the process that wrote the journal: a client
        on another machine may see an older size of a file on a shared file
        system, and the manifest's size is what load() keeps of the journal.
        """
        if not self.database.append_journal(path):
            return False, 0
        try:
            return True, os.path.getsize(path + _JOURNAL)
        except FileNotFoundError:  # nothing changed since the last save
            return True, 0

    def call(self, method, *arguments):
        """(result, None) of a Database method, or (None, its exception).

        The shard's own errors travel as values, so that an exception raised
        by the actor call itself always means the shard is unreachable.
        """
        try:
            if method == "add_many":
                return self.add_many(*arguments), None
            if method == "contains":
                return arguments[0] in self.database, None
            if method == "size":
                return len(self.database), None
            if method == "next_entry_id":
                return self.database.next_entry_id, None
            if method == "options":
                return {"direct_index": self.database.direct_index,
                        "levels_up": self.database.levels_up}, None
            if method == "save":
                # Database.save writes a temporary file and renames it: atomic.
                return self.database.save(arguments[0], include_vocabulary=False), None
            if method == "append_journal":
                return self.append_journal(arguments[0]), None
            if method == "query":  # (image, max_results, max_entry_id, fast, fast keywords)
                *positional, keywords = arguments
                return self.database.query(*positional, **keywords), None
            return getattr(self.database, method)(*arguments), None
        except Exception as error:
            return None, error


_JOURNAL = ".journal"  # Database.journal_path: beside each shard's file


# A shard's file is only ever written whole under a name no manifest names
# yet: a new generation of shard files (every shard's for a full save, the
# shards whose journal is full for an incremental one). A shard's Database
# stays tied to the name it wrote (so that the next save_incremental appends
# to its journal), while the files the manifest names stay whole until the
# next manifest replaces it. A manifest may also name shard-<i>.bbdb, a file
# without generation.
_SHARD_FILE = re.compile(r"shard-[0-9]+(?:\.gen([0-9]+))?\.bbdb(?:\.journal)?")
# The temporaries of a save that was killed: those binbow writes beside a
# shard file, and the manifest's. Each is flock()ed while its writer lives.
# The writer lock binbow takes beside a shard file while saving it (DatabaseLock).
_SHARD_LOCK = re.compile(r"(shard-[0-9]+(?:\.gen[0-9]+)?\.bbdb)\.lock")
_TEMPORARY = re.compile(r"(?:shard-[0-9]+(?:\.gen[0-9]+)?\.bbdb(?:\.journal)?|"
                        r"manifest\.json)\.tmp-[0-9A-Za-z]{6}")


def _shard_files(shards, generation):
    return [f"shard-{shard}.gen{generation}.bbdb" for shard in range(shards)]


def _next_generation(folder):
    """One past the newest generation of shard files in `folder`, so that a save
    never writes over a file that a manifest may name."""
    newest = 0
    with os.scandir(folder) as found:
        for entry in found:
            match = _SHARD_FILE.fullmatch(entry.name)
            if match and match.group(1) and entry.is_file(follow_symlinks=False):
                newest = max(newest, int(match.group(1)))
    return newest + 1


def _named_files(files):
    """The shard files a manifest naming `files` reads: each file and its journal."""
    return set(files) | {name + _JOURNAL for name in files}


def _remove_if_abandoned(path):
    """Removes a temporary or a lock file that no live writer holds."""
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        return
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.unlink(path)
    except OSError:  # held by its writer, or gone already
        pass
    finally:
        os.close(descriptor)


def _remove_shard_files(folder, keep):
    """Removes the shard files, journals and writer locks in `folder` that `keep`
    does not name, and the temporaries of dead saves; nothing else in the folder."""
    with os.scandir(folder) as found:
        entries = [(entry.name, entry.path) for entry in found
                   if entry.is_file(follow_symlinks=False)]
    for name, path in entries:
        if _SHARD_FILE.fullmatch(name) and name not in keep:
            try:
                os.unlink(path)
            except FileNotFoundError:
                pass
        elif _TEMPORARY.fullmatch(name):
            _remove_if_abandoned(path)
        else:
            lock = _SHARD_LOCK.fullmatch(name)
            if lock and lock.group(1) not in keep:
                _remove_if_abandoned(path)


def _sync_folder(folder):
    """Flushes the folder's entries to disk: the renames and new files in it."""
    descriptor = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
    try:
        os.fsync(descriptor)
    except OSError as error:
        if error.errno != errno.EINVAL:  # a file system that cannot sync a folder
            raise
    finally:
        os.close(descriptor)


def _replace_manifest(folder, manifest):
    """Replaces folder/manifest.json with `manifest` in one rename.

    The temporary is created with the permissions the umask asks for (as
    binbow's own saves), locked while it is written (a load removes the
    temporaries it can lock), and flushed to disk before the rename.
    """
    path = os.path.join(folder, _MANIFEST)
    data = json.dumps(manifest, indent=2).encode("utf-8")
    for _ in range(100):
        temporary = f"{path}.tmp-{secrets.token_hex(3)}"
        try:
            descriptor = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC,
                                 0o666)
            break
        except FileExistsError:
            continue
    else:
        raise Error(f"ShardedDatabase: cannot create a temporary file beside {path}")
    try:
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # a file system without locks: go on
            pass
        view = memoryview(data)
        while view:
            view = view[os.write(descriptor, view):]
        os.fsync(descriptor)
        os.replace(temporary, path)
    except BaseException:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        raise
    finally:
        os.close(descriptor)


def _cut_journal(journal, size, manifest):
    """Cuts a shard's journal to the size the manifest committed: what follows
    is a save that never finished writing the manifest."""
    found = os.path.getsize(journal) if os.path.exists(journal) else 0
    if found < size:
        raise Error(f"ShardedDatabase.load: {journal} has {found} bytes, {manifest} "
                    f"says {size}")
    if found > size:
        if size == 0:
            os.unlink(journal)
        else:
            os.truncate(journal, size)


def _shard_size(entries, shard, shards):
    """How many of the global ids 0..entries-1 route to `shard`."""
    return max(0, (entries - shard + shards - 1) // shards)


def _checked_image(image, vocabulary, what):
    """Database.add's checks and errors, made before any shard adds anything."""
    if isinstance(image, BowVector):
        _check_bow(image, vocabulary)
        return image
    return _checked_descriptors(image, what, vocabulary.code_size)


def _no_entry(method, entry, entries):
    """Database's ValueError for an id that does not exist."""
    return ValueError(f"Database::{method}: entry {entry} does not exist (the database has "
                      f"ids below {entries})")


def _lost_shard(where, shard, reason):
    """The error of every call once a shard is lost, the call that finds it included."""
    return Error(f"{where}: shard {shard} was lost ({reason}); its entries are gone, so this "
                 "database no longer answers as one Database: is the Dask cluster alive? A "
                 "shard lost with its worker can only come back from the last save: load the "
                 "last save (ShardedDatabase.load)")


class ShardedDatabase:
    """One binbow.Database per shard on the workers of a Dask cluster.

    ShardedDatabase(client, vocabulary, shards=N, timeout=120, **database_options):
    `client` is a distributed.Client, `database_options` go to every shard's
    binbow.Database (direct_index, levels_up). Shards are spread round-robin over
    the cluster's workers as Dask actors. Every call to a shard gives up with
    binbow.Error after `timeout` seconds.
    """

    def __init__(self, client, vocabulary, shards=1, timeout=DEFAULT_TIMEOUT,
                 **database_options):
        self._setup(client, vocabulary, shards, timeout)
        self._entries = 0
        self._start([(database_options, None)] * shards)

    def _setup(self, client, vocabulary, shards, timeout):
        distributed = _distributed()
        if not isinstance(client, distributed.Client):
            raise TypeError(f"ShardedDatabase: client must be a distributed.Client, "
                            f"got {type(client).__name__}")
        if not isinstance(vocabulary, Vocabulary):
            raise TypeError(f"ShardedDatabase: vocabulary must be a binbow.Vocabulary, "
                            f"got {type(vocabulary).__name__}")
        if isinstance(shards, bool) or not isinstance(shards, int) or shards < 1:
            raise ValueError(f"ShardedDatabase: shards must be a positive integer, got {shards!r}")
        if not timeout > 0:
            raise ValueError(f"ShardedDatabase: timeout must be positive seconds, got {timeout!r}")
        self._client = client
        self._saved_folder = None  # of the last save or load, which incremental saves extend
        self._saved_files = None  # the shard files there, as its manifest names them
        self._vocabulary = vocabulary
        self._timeout = float(timeout)
        self._shard_count = shards

    def _start(self, arguments):
        """Starts a shard per (database options, file to load) pair."""
        workers = sorted(self._client.scheduler_info()["workers"])
        if not workers:
            raise Error("ShardedDatabase: the Dask cluster has no workers")
        placed = [workers[shard % len(workers)] for shard in range(len(arguments))]
        # Sent once to each worker rather than in every shard's task: the shards
        # of a worker share one copy, and no large task passes the scheduler.
        try:
            vocabulary = self._client.scatter(self._vocabulary, workers=sorted(set(placed)),
                                              broadcast=True, hash=False,
                                              timeout=self._timeout)
        except Exception as error:
            raise Error(f"ShardedDatabase: sending the vocabulary to the workers failed "
                        f"({type(error).__name__}: {error}): is the Dask cluster alive?") \
                from error
        futures = [
            self._client.submit(_Shard, vocabulary, *argument, actor=True, pure=False,
                                workers=[worker], allow_other_workers=False)
            for worker, argument in zip(placed, arguments)
        ]
        self._actor_futures = futures  # keep the actors alive
        self._lost = {}  # shard: what failed
        self._shards = [self._wait(future, f"starting shard {shard}")
                        for shard, future in enumerate(futures)]
        self.workers = placed

    def _wait(self, future, what, shard=None, changes=False):
        """The result of a Dask future or actor call; binbow.Error when it cannot be had.

        A shard that cannot be reached (its worker died) is lost for good, and so
        is one that timed out while changing: its entries are unknown.
        """
        try:
            if isinstance(future, BaseException):  # the call could not even be sent
                raise future
            return future.result(timeout=self._timeout)
        except (TimeoutError, _distributed().TimeoutError) as error:
            failure = error
            reason = f"took more than {self._timeout:g} s (timeout=)"
            lost = changes
        except Exception as error:  # a worker that died: CommClosedError, lost actor, ...
            failure = error
            reason = f"failed ({type(error).__name__}: {error})"
            lost = True
        if lost and shard is not None:
            # Said as every later call says it, however Dask reported the loss
            # (a timeout first, then a lost actor, or at once).
            self._lost.setdefault(shard, f"{what} {reason}")
            raise _lost_shard("ShardedDatabase", shard, f"{what} {reason}") from failure
        raise Error(f"ShardedDatabase: {what} {reason}: is the Dask cluster alive? "
                    "A shard lost with its worker can only come back from the last save "
                    "(ShardedDatabase.load)") from failure

    def _check_usable(self, what):
        """binbow.Error if a shard was lost: its entries would silently be missing."""
        if self._lost:
            shard, reason = min(self._lost.items())
            raise _lost_shard(f"ShardedDatabase.{what}", shard, reason)

    def _call_all(self, what, method, arguments, changes=False):
        """Calls `method` on every shard with its own arguments (None: skip); the results.

        Every answer is awaited before any error is raised, so that every lost
        shard is known; a shard's own error (ValueError, OSError, ...) is raised as is.
        """
        futures = {}
        for shard, argument in enumerate(arguments):
            if argument is not None:
                try:
                    futures[shard] = self._shards[shard].call(method, *argument)
                except Exception as error:  # Dask knows the actor's worker is gone
                    futures[shard] = error
        answers, failure = {}, None
        for shard, future in futures.items():
            try:
                answers[shard] = self._wait(future, f"{what} on shard {shard}", shard, changes)
            except Error as error:
                failure = failure or error
        if failure is not None:
            raise failure
        for shard, (_, error) in answers.items():
            if error is not None:
                raise error
        return {shard: value for shard, (value, _) in answers.items()}

    def _on_entry(self, method, entry, *arguments, changes=False):
        """Calls `method` for a global entry id on its shard, with Database's errors."""
        self._check_usable(method)
        if isinstance(entry, bool) or not isinstance(entry, (int, _np.integer)):
            raise TypeError(f"ShardedDatabase.{method}: entry must be an integer id, "
                            f"got {type(entry).__name__}")
        entry = int(entry)
        if entry < 0 or entry >= self._entries:
            raise _no_entry(method, entry, self._entries)
        shard, local = entry % self._shard_count, entry // self._shard_count
        per_shard = [None] * self._shard_count
        per_shard[shard] = (local, *arguments)
        try:
            return self._call_all(method, method, per_shard, changes)[shard]
        except ValueError as error:
            if "was removed" in str(error):  # the shard names its own id
                raise ValueError(f"Database::{method}: entry {entry} was removed") from None
            raise

    def add(self, image, label=None):
        """Adds one image (descriptors or a BowVector); its id, as Database.add gives."""
        return self._add([image], None if label is None else [label], "add",
                         lambda index: "descriptors")[0]

    def add_many(self, images, labels=None):
        """Adds images (descriptors or BowVectors) in order, one round trip per shard.

        Returns their ids: the next ids in order, as repeated Database.add calls give.
        Everything is checked before any shard adds anything, with Database.add's
        errors (descriptors are named images[i]).
        """
        images = list(images)
        if labels is not None:
            labels = list(labels)
            if len(labels) != len(images):
                raise ValueError(f"ShardedDatabase.add_many: {len(images)} images but "
                                 f"{len(labels)} labels")
        return self._add(images, labels, "add_many", lambda index: f"images[{index}]")

    def _add(self, images, labels, what, name):
        self._check_usable(what)
        checked = [_checked_image(image, self._vocabulary, name(index))
                   for index, image in enumerate(images)]
        if labels is not None:
            labels = [_label_argument(label) or None for label in labels]
        first = self._entries
        batches = [[] for _ in range(self._shard_count)]
        for index, image in enumerate(checked):
            label = None if labels is None else labels[index]
            batches[(first + index) % self._shard_count].append((image, label))
        answers = self._call_all(what, "add_many",
                                 [(batch,) if batch else None for batch in batches], changes=True)
        failures = [(shard, error) for shard, (_, error) in answers.items() if error is not None]
        if failures:
            shard, error = failures[0]
            self._lost.setdefault(shard, f"{what} failed part way ({error})")
            raise Error(f"ShardedDatabase.{what}: shard {shard} failed ({error}); shards "
                        "that added their part keep it, so ids no longer match a single "
                        "Database: load the last save") from error
        for shard, (local_ids, _) in answers.items():
            expected = _shard_size(first, shard, self._shard_count)
            if local_ids and local_ids[0] != expected:
                raise Error(f"ShardedDatabase.{what}: shard {shard} gave id {local_ids[0]}, "
                            f"expected {expected}: another client changed it")
        self._entries = first + len(images)
        return list(range(first, self._entries))

    def transform(self, image):
        """The BowVector of descriptors (a BowVector is returned as is)."""
        if isinstance(image, BowVector):
            return image
        if image is not None and not isinstance(image, _np.ndarray):
            raise TypeError("image must be a BowVector or descriptors (a numpy uint8 array), "
                            f"got {type(image).__name__}")
        return self._vocabulary.transform(image)

    def query(self, image, max_results=10, max_entry_id=None, fast=False, *,
              fast_candidates=None, fast_candidate_share=None, fast_min_postings=None):
        """Best matches as (entry, score, shared_words), best first, as Database.query.

        The image (descriptors or BowVector) is transformed once here; every shard
        returns its own top `max_results` and the lists are merged: any entry of the
        overall top list is in its shard's top list, and scores do not depend on the
        shard, so the result equals one Database's, ties (by increasing id) included.
        With fast=True every shard answers in Database's fast mode (exact scores,
        candidates from the rarest words); the merge is the same.
        fast_candidates, fast_candidate_share and fast_min_postings (fast=True only)
        go to every shard's Database.query, which would refuse the same values:
        they are refused here with its errors, before any shard is called. Each
        shard applies them to its own entries, as a Database of those entries
        would: a fast_candidate_share that is set is a share of the shard's
        entries, so the candidates of all shards are that share of the whole
        database (the default share grows with each shard's own entries, as a
        Database's does), while fast_candidates and fast_min_postings count per
        shard (shards times as many in all).
        """
        if not isinstance(fast, bool):
            raise TypeError(f"fast must be a bool, got {type(fast).__name__}")
        _check_query_options(fast, fast_candidates, fast_candidate_share, fast_min_postings)
        tuning = {name: value for name, value in (("fast_candidates", fast_candidates),
                                                  ("fast_candidate_share", fast_candidate_share),
                                                  ("fast_min_postings", fast_min_postings))
                  if value is not None}
        self._check_usable("query")
        max_results = _count_argument(max_results, "max_results")
        if max_entry_id is not None:
            max_entry_id = _count_argument(max_entry_id, "max_entry_id")
        bow = self.transform(image)
        if max_results == 0 or len(bow) == 0:
            return []
        n = self._shard_count
        arguments = []
        for shard in range(n):
            if max_entry_id is None:
                arguments.append((bow, max_results, None, fast, tuning))
            elif max_entry_id >= shard:
                arguments.append((bow, max_results, (int(max_entry_id) - shard) // n, fast,
                                  tuning))
            else:
                arguments.append(None)
        answers = self._call_all("query", "query", arguments)
        merged = [(shard + local * n, score, shared)
                  for shard, results in answers.items() for local, score, shared in results]
        return sorted(merged, key=self._ranking)[:max_results]

    @property
    def _ranking(self):
        """Database's order: best score first (lowest for KL), NaN last, then lowest id."""
        sign = 1 if self._vocabulary.scoring == "kl" else -1

        def key(result):
            score = result[1]
            return (math.inf if math.isnan(score) else sign * score, result[0])
        return key

    def remove(self, entry):
        """Removes an entry; its id is never reused. ValueError if it does not exist."""
        self._on_entry("remove", entry, changes=True)

    def label(self, entry):
        """The entry's label, None if it has none."""
        return self._on_entry("label", entry)

    def set_label(self, entry, label):
        """Sets (or with "", removes) an entry's label."""
        self._on_entry("set_label", entry, label, changes=True)

    def __contains__(self, entry):
        try:
            return self._on_entry("contains", entry)
        except ValueError:
            return False

    def __len__(self):
        self._check_usable("__len__")
        return sum(self._call_all("len", "size", [()] * self._shard_count).values())

    @property
    def next_entry_id(self):
        """The id the next add returns."""
        return self._entries

    @property
    def shards(self):
        """The number of shards."""
        return self._shard_count

    @property
    def vocabulary(self):
        """The vocabulary every shard uses."""
        return self._vocabulary

    def save(self, folder):
        """Saves shard-<i>.gen<g>.bbdb per shard (written by its worker) and manifest.json.

        `folder` must be reachable at the same path from the workers and the
        client (a shared file system when they are on several machines). A
        database that lost a shard is refused (binbow.Error) before anything is
        written. The shards write a new generation <g> of files beside the
        previous save, which stays until the manifest, replaced in one rename,
        names the new one: a save stopped at any point (a lost shard, a killed
        process) leaves the previous save or this one loadable, never a mix.
        Then the previous generation's files and journals are removed.
        """
        self._check_usable("save")
        folder = os.path.abspath(os.fspath(folder))
        # Every shard must answer before any writes (binbow.Error otherwise).
        options = self._call_all("save", "options", [()] * self._shard_count)[0]
        os.makedirs(folder, exist_ok=True)
        self._saved_folder = None  # until the manifest commits: the shards' files change
        files = _shard_files(self._shard_count, _next_generation(folder))
        self._commit(folder, files, options, [0] * self._shard_count, written=range(len(files)),
                     what="save")

    def save_incremental(self, folder):
        """Appends each shard's changes since the last save to its journal, then
        rewrites manifest.json, which records each journal's size.

        A save to another folder than this database's last save or load is a
        full save(folder). Each shard appends with Database.append_journal. A
        shard whose journal would pass a quarter of its file (or that cannot
        append) writes its file whole instead, under a new generation's name:
        the files the manifest names are only ever appended to. The manifest,
        replaced last in one rename, is what a load follows: records appended
        after the manifest's sizes and files it does not name (a save that did
        not finish) are dropped by load(). Then the rewritten shards' previous
        files are removed.
        """
        self._check_usable("save_incremental")
        folder = os.path.abspath(os.fspath(folder))
        if self._saved_folder != folder:
            self.save(folder)
            return
        options = self._call_all("save_incremental", "options", [()] * self._shard_count)[0]
        files = list(self._saved_files)
        appended = self._call_all("save_incremental", "append_journal",
                                  [(os.path.join(folder, name),) for name in files])
        rewritten = [shard for shard in range(self._shard_count) if not appended[shard][0]]
        if rewritten:
            generation = _next_generation(folder)
            for shard in rewritten:
                files[shard] = f"shard-{shard}.gen{generation}.bbdb"
        sizes = [appended[shard][1] for shard in range(self._shard_count)]
        self._commit(folder, files, options, sizes, written=rewritten, what="save_incremental")

    def _commit(self, folder, files, options, journal_bytes, written, what):
        """Has the shards in `written` save their files whole under their new names
        in `files`, replaces the manifest, then removes the files it no longer
        names. Until the manifest is replaced, nothing it named has changed but
        journals grown past its sizes; if anything fails before, the new files
        are removed and the previous save stays as it was.
        """
        paths = [os.path.join(folder, name) for name in files]
        written = set(written)
        try:
            if written:
                self._call_all(what, "save", [(paths[shard],) if shard in written else None
                                              for shard in range(self._shard_count)])
            self._write_manifest(folder, files, options, journal_bytes)
        except BaseException:
            for shard in written:  # none of them existed before this save
                if os.path.isfile(paths[shard]):
                    os.unlink(paths[shard])
            raise
        # The new manifest on disk before the files of the previous one go.
        _sync_folder(folder)
        if written:
            _remove_shard_files(folder, keep=_named_files(files))

    def _write_manifest(self, folder, files, options, journal_bytes):
        manifest = {
            "format": _FORMAT,
            "version": _FORMAT_VERSION,
            "shards": self._shard_count,
            "routing": "entry id % shards, stored under entry id // shards",
            "next_entry_id": self._entries,
            "vocabulary_checksum": self._vocabulary.checksum,
            "database_options": options,
            "files": files,
            "journal_bytes": journal_bytes,
        }
        _replace_manifest(folder, manifest)
        self._saved_folder = folder
        self._saved_files = files

    @classmethod
    def load(cls, client, folder, vocabulary, timeout=DEFAULT_TIMEOUT):
        """A ShardedDatabase saved by save(folder); `vocabulary` must be the saved one."""
        folder = os.path.abspath(os.fspath(folder))
        path = os.path.join(folder, _MANIFEST)
        try:
            with open(path, encoding="utf-8") as file:
                manifest = json.load(file)
        except OSError as error:
            raise Error(f"ShardedDatabase.load: cannot read {path}: {error}") from error
        except ValueError as error:
            raise Error(f"ShardedDatabase.load: {path} is not JSON: {error}") from error
        try:
            if manifest["format"] != _FORMAT or manifest["version"] != _FORMAT_VERSION:
                raise Error(f"ShardedDatabase.load: {path} is not a version {_FORMAT_VERSION} "
                            f"{_FORMAT} manifest")
            shards = manifest["shards"]
            entries = manifest["next_entry_id"]
            files = manifest["files"]
            checksum = manifest["vocabulary_checksum"]
        except (KeyError, TypeError) as error:
            raise Error(f"ShardedDatabase.load: {path} lacks {error}") from error
        if (not isinstance(shards, int) or shards < 1 or not isinstance(entries, int)
                or entries < 0 or not isinstance(files, list) or len(files) != shards
                or not all(isinstance(name, str) and os.path.basename(name) == name
                           for name in files)):
            raise Error(f"ShardedDatabase.load: {path} has an invalid shards, next_entry_id "
                        "or files field")
        journal_bytes = manifest.get("journal_bytes", [0] * shards)
        if (not isinstance(journal_bytes, list) or len(journal_bytes) != shards
                or not all(isinstance(size, int) and size >= 0 for size in journal_bytes)):
            raise Error(f"ShardedDatabase.load: {path} has an invalid journal_bytes field")
        if isinstance(vocabulary, Vocabulary) and checksum != vocabulary.checksum:
            raise Error(f"ShardedDatabase.load: {path} was saved with vocabulary checksum "
                        f"{checksum}, this vocabulary's is {vocabulary.checksum}")
        for name, size in zip(files, journal_bytes):
            _cut_journal(os.path.join(folder, name) + _JOURNAL, size, path)
        self = cls.__new__(cls)
        self._setup(client, vocabulary, shards, timeout)
        self._saved_folder = folder
        self._saved_files = files
        self._entries = entries
        self._start([(None, os.path.join(folder, name)) for name in files])
        found = self._call_all("load", "next_entry_id", [()] * shards)
        for shard, next_id in found.items():
            if next_id != _shard_size(entries, shard, shards):
                raise Error(f"ShardedDatabase.load: {files[shard]} holds {next_id} ids, "
                            f"{path} says {_shard_size(entries, shard, shards)}")
        # What a save that did not finish left: only once the files the
        # manifest names have loaded, so that a wrong manifest removes nothing.
        _remove_shard_files(folder, keep=_named_files(files))
        return self
