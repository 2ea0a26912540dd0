"""Real images: one binbow.Database against a ShardedDatabase on 2 Dask workers.

The same entries, made as bench/database_scale.cpp makes them: ORB-1000
descriptors of the training photographs (scripts/training_images.sh --all;
small ones enlarged until they give 1000), every tenth photograph held out
for the queries (two noisy copies each), every database entry one of the
others with a few random bits flipped in every descriptor (seeded by its id),
added with its direct index 4 levels up. Each photograph's descriptors are
extracted once; the noisy copies are made with numpy as they are added.

The one Database is built, measured and freed first, then the ShardedDatabase
(2 shards on a LocalCluster of 2 worker processes, 1 thread each) at the same
total size, so both never hold memory at the same time. Measured for each:
query time (top 10, exact and fast; queries are BowVectors, so only the query
is timed), resident memory (VmRSS) of the process(es) holding the entries,
a full save, then a save_incremental after adding 1 % more entries.

    BINBOW_BENCH_VOCABULARY=<trained .bbw> \\
        PYTHONPATH=build/python python3 bench/sharded_scale.py --entries 200000

The vocabulary comes from scripts/make_benchmark_vocabulary.sh; the saves go
to a temporary folder in $BINBOW_BENCH_DIR (default /tmp), removed at the end.
"""
import argparse
import ctypes
import gc
import os
import shutil
import statistics
import subprocess
import tempfile
import time

import cv2
import numpy as np

import binbow

SOURCE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FEATURES = 1000
LEVELS_UP = 4
MAX_RESULTS = 10
NOISY_COPIES_PER_QUERY = 2
QUERY_SEED = 0x9000000000  # bench/database_scale.cpp's, far from the entries' ids
BATCH = 1000  # entries per ShardedDatabase.add_many


def training_photographs():
    script = os.path.join(SOURCE_DIR, "scripts", "training_images.sh")
    listed = subprocess.run([script, "--all"], capture_output=True, text=True, check=True)
    return listed.stdout.split("\n")[:-1]


def thousand_descriptors(extractor, path):
    """1000 descriptors of a photograph, at its size or enlarged 2 or 4 times;
    None if it never gives them."""
    image = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise SystemExit(f"sharded_scale: cannot read {path}")
    for attempt in range(3):
        if attempt > 0:
            image = cv2.resize(image, None, fx=2.0, fy=2.0)
        _, descriptors = extractor.extract(image)
        if len(descriptors) >= FEATURES:
            return np.ascontiguousarray(descriptors[:FEATURES])
    return None


def flipped(descriptors, seed, bits):
    """A copy of the descriptors with `bits` random bits flipped in each row
    (bit b is bit b % 8 of byte b / 8; a bit drawn twice flips back)."""
    rows, width = descriptors.shape
    chosen = np.random.default_rng(seed).integers(0, width * 8, size=(bits, rows),
                                                  dtype=np.uint64)
    words, ones = chosen >> np.uint64(6), np.uint64(1) << (chosen & np.uint64(63))
    mask = np.empty((rows, width // 8), dtype="<u8")
    for word in range(width // 8):
        mask[:, word] = np.bitwise_xor.reduce(ones * (words == word), axis=0)
    return descriptors ^ mask.view(np.uint8)


def resident_bytes():
    """VmRSS of the calling process (also run on the Dask workers)."""
    with open("/proc/self/status", encoding="ascii") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmRSS in /proc/self/status")


def cpu_seconds():
    """User + system CPU time of the calling process (also run on the workers)."""
    times = os.times()
    return times.user + times.system


def shard_memory_usage(dask_worker):
    """Database.memory_usage of the shards a worker holds (its actors)."""
    actors = getattr(dask_worker, "state", dask_worker).actors
    return sum(actor.database.memory_usage for actor in actors.values()
               if hasattr(actor, "database"))


def release_freed_memory():
    gc.collect()
    ctypes.CDLL("libc.so.6").malloc_trim(0)


def timed_queries(query, bows, fast):
    """Median wall ms of query(bow, fast) over the bows, and the answers."""
    query(bows[0], fast)  # touches the lazily built state (fast mode's forward index)
    times, answers = [], []
    for bow in bows:
        start = time.perf_counter()
        answers.append(query(bow, fast))
        times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(times), answers


def timed(function):
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def folder_bytes(folder, suffix):
    return sum(os.path.getsize(os.path.join(folder, name)) for name in os.listdir(folder)
               if name.endswith(suffix))


class Entries:
    """Entry `id`: photograph id % photographs with its own noise."""

    def __init__(self, photographs, bits):
        self.photographs = photographs
        self.bits = bits

    def __call__(self, first, end):
        return [flipped(self.photographs[entry % len(self.photographs)], entry, self.bits)
                for entry in range(first, end)]


def measure_single(vocabulary, entries, count, growth, queries, folder):
    result = {}
    release_freed_memory()
    before = resident_bytes()
    database = binbow.Database(vocabulary, direct_index=True, levels_up=LEVELS_UP)
    start = time.perf_counter()
    for first in range(0, count, BATCH):
        for descriptors in entries(first, min(count, first + BATCH)):
            database.add(descriptors)
    result["build_s"] = time.perf_counter() - start
    result["rss"] = resident_bytes()
    result["rss_database"] = result["rss"] - before
    result["memory_usage"] = database.memory_usage

    def query(bow, fast):
        return database.query(bow, MAX_RESULTS, fast=fast)
    cpu = cpu_seconds()  # of every thread: a large database's query uses every core
    result["exact_ms"], result["exact"] = timed_queries(query, queries, False)
    result["exact_cpu_ms"] = (cpu_seconds() - cpu) * 1e3 / (len(queries) + 1)
    result["fast_ms"], result["fast"] = timed_queries(query, queries, True)
    result["rss_fast"] = resident_bytes()  # with fast mode's forward index

    path = os.path.join(folder, "single.bbdb")
    result["save_s"] = timed(lambda: database.save(path, include_vocabulary=False))
    result["save_bytes"] = os.path.getsize(path)
    for descriptors in entries(count, count + growth):
        database.add(descriptors)
    result["incremental_s"] = timed(
        lambda: database.save_incremental(path, include_vocabulary=False))
    journal = path + ".journal"  # none: the incremental save wrote the file whole
    result["incremental_bytes"] = os.path.getsize(journal) if os.path.exists(journal) else 0
    return result  # and the database is freed


def measure_sharded(vocabulary, entries, count, growth, queries, folder, workers):
    import distributed
    from binbow.distributed import ShardedDatabase

    result = {}
    with distributed.LocalCluster(n_workers=workers, processes=True, threads_per_worker=1,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        sharded = ShardedDatabase(client, vocabulary, shards=workers, timeout=1800,
                                  direct_index=True, levels_up=LEVELS_UP)
        before = client.run(resident_bytes)
        start = time.perf_counter()
        for first in range(0, count, BATCH):
            sharded.add_many(entries(first, min(count, first + BATCH)))
        result["build_s"] = time.perf_counter() - start
        after = client.run(resident_bytes)
        result["rss"] = [after[worker] for worker in sharded.workers]
        result["rss_database"] = [after[worker] - before[worker] for worker in sharded.workers]
        usage = client.run(shard_memory_usage)
        result["memory_usage"] = [usage[worker] for worker in sharded.workers]

        def query(bow, fast):
            return sharded.query(bow, MAX_RESULTS, fast=fast)
        cpu = client.run(cpu_seconds)
        result["exact_ms"], result["exact"] = timed_queries(query, queries, False)
        cpu_after = client.run(cpu_seconds)
        result["exact_cpu_ms"] = [(cpu_after[worker] - cpu[worker]) * 1e3 / (len(queries) + 1)
                                  for worker in sharded.workers]
        result["fast_ms"], result["fast"] = timed_queries(query, queries, True)
        after = client.run(resident_bytes)
        result["rss_fast"] = [after[worker] for worker in sharded.workers]
        result["empty_call_ms"], _ = timed_queries(lambda bow, fast: len(sharded), queries, False)

        saved = os.path.join(folder, "sharded")
        result["save_s"] = timed(lambda: sharded.save(saved))
        result["save_bytes"] = folder_bytes(saved, ".bbdb")
        sharded.add_many(entries(count, count + growth))
        result["incremental_s"] = timed(lambda: sharded.save_incremental(saved))
        result["incremental_bytes"] = folder_bytes(saved, ".journal")
        result["incremental_whole_files"] = result["incremental_bytes"] == 0
    return result


def mib(value):
    return f"{value / 2**20:,.0f} MiB"


def both(single, sharded, format_value):
    return f"| {format_value(single)} | " + " / ".join(format_value(v) for v in sharded) + " |"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vocabulary", default=os.environ.get("BINBOW_BENCH_VOCABULARY"),
                        help="the trained vocabulary (default: $BINBOW_BENCH_VOCABULARY)")
    parser.add_argument("--entries", type=int, default=200000)
    parser.add_argument("--workers", type=int, default=2, help="worker processes = shards")
    parser.add_argument("--flipped-bits", type=int, default=8, help="per descriptor, of 256")
    parser.add_argument("--folder", default=os.environ.get("BINBOW_BENCH_DIR", "/tmp"),
                        help="where the saves go (deleted afterwards)")
    arguments = parser.parse_args()
    if not arguments.vocabulary:
        parser.error("give --vocabulary or set BINBOW_BENCH_VOCABULARY to a vocabulary from "
                     "scripts/make_benchmark_vocabulary.sh")
    vocabulary = binbow.Vocabulary.load(arguments.vocabulary)
    extractor = binbow.FeatureExtractor("orb", FEATURES)

    start = time.perf_counter()
    photographs, queries = [], []
    for index, path in enumerate(training_photographs()):
        descriptors = thousand_descriptors(extractor, path)
        if descriptors is None:
            continue
        if index % 10 != 9:
            photographs.append(descriptors)
            continue
        for copy in range(NOISY_COPIES_PER_QUERY):
            seed = QUERY_SEED + index * NOISY_COPIES_PER_QUERY + copy
            queries.append(vocabulary.transform(flipped(descriptors, seed, arguments.flipped_bits)))
    if len(photographs) < 100 or not queries:
        raise SystemExit(f"sharded_scale: too few training photographs with {FEATURES} ORB "
                         f"features ({len(photographs)}): run scripts/training_images.sh --all")
    extraction_s = time.perf_counter() - start
    entries = Entries(photographs, arguments.flipped_bits)
    count = arguments.entries
    growth = max(1, count // 100)

    folder = tempfile.mkdtemp(prefix="binbow-sharded-scale-", dir=arguments.folder)
    try:
        single = measure_single(vocabulary, entries, count, growth, queries, folder)
        release_freed_memory()
        sharded = measure_sharded(vocabulary, entries, count, growth, queries, folder,
                                  arguments.workers)
    finally:
        shutil.rmtree(folder)

    same_exact = sum(a == b for a, b in zip(single["exact"], sharded["exact"]))
    same_fast = sum(a == b for a, b in zip(single["fast"], sharded["fast"]))
    fast_top10 = [sum(a == b for a, b in zip(run["exact"], run["fast"]))
                  for run in (single, sharded)]
    uptime = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; uptime: {uptime}")
    print(f"{count:,} entries from {len(photographs)} photographs ({extraction_s:.0f} s to "
          f"extract), {len(queries)} queries, top {MAX_RESULTS}; vocabulary "
          f"{vocabulary.word_count:,} words ({os.path.basename(arguments.vocabulary)}); "
          f"{arguments.workers} workers x 1 thread")
    print(f"same answers as the one Database: exact {same_exact}/{len(queries)}, "
          f"fast {same_fast}/{len(queries)}; fast top 10 = exact top 10: one process "
          f"{fast_top10[0]}/{len(queries)}, sharded {fast_top10[1]}/{len(queries)}")
    print(f"| | one process | {arguments.workers} workers (each) |")
    print("|---|---|---|")
    print("| exact query, median ms " + both(single["exact_ms"], [sharded["exact_ms"]],
                                               "{:.1f}".format))
    print("| exact query, CPU ms per query (every thread) " + both(single["exact_cpu_ms"],
                                                      sharded["exact_cpu_ms"], "{:.1f}".format))
    print("| fast query, median ms " + both(single["fast_ms"], [sharded["fast_ms"]],
                                              "{:.1f}".format))
    print(f"| empty call to every shard, median ms | | {sharded['empty_call_ms']:.1f} |")
    print("| resident memory of the entries (VmRSS growth) " +
          both(single["rss_database"], sharded["rss_database"], mib))
    print("| resident memory of the process " + both(single["rss"], sharded["rss"], mib))
    print("| resident memory of the process after fast queries " + both(
        single["rss_fast"], sharded["rss_fast"], mib))
    print("| Database.memory_usage " + both(single["memory_usage"], sharded["memory_usage"],
                                             mib))
    print("| adding the entries (the client makes the noisy copies), s " + both(single["build_s"], [sharded["build_s"]],
                                            "{:.0f}".format))
    print("| full save, s (bytes) " + both(
        (single["save_s"], single["save_bytes"]), [(sharded["save_s"], sharded["save_bytes"])],
        lambda v: f"{v[0]:.2f} ({mib(v[1])})"))
    whole = " (whole files)" if sharded["incremental_whole_files"] else ""
    print(f"| save_incremental after +{growth:,} entries, s (journal bytes) " + both(
        (single["incremental_s"], single["incremental_bytes"]),
        [(sharded["incremental_s"], sharded["incremental_bytes"])],
        lambda v: f"{v[0]:.2f} ({mib(v[1])})") + whole)


if __name__ == "__main__":
    main()
