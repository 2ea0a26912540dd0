"""Query throughput of binbow.distributed.ShardedDatabase versus shards and workers.

Synthetic entries: random BowVectors (300 words each, drawn from the default
ORB vocabulary, L1-normalised values), so no feature extraction is timed.
Every configuration answers the same queries (top 10) one after the other from
one client; the per-query time is split into what the shards compute, the
pickling of the query and of the answers, the client's merge, and the rest
(Dask's messages between processes: IPC here, the network on a cluster),
which the last column measures directly with a call that does nothing.

    PYTHONPATH=build/python python3 bench/sharded_database.py [--entries 20000]
"""
import argparse
import pickle
import statistics
import time

import numpy as np

import binbow
from binbow.distributed import ShardedDatabase


def synthetic_bows(vocabulary, count, words, seed):
    rng = np.random.default_rng(seed)
    bows = []
    for _ in range(count):
        chosen = np.unique(rng.integers(0, vocabulary.word_count, size=words))
        values = rng.random(len(chosen)).astype(np.float32)
        bows.append(binbow.BowVector(chosen.astype(np.uint32), values / values.sum()))
    return bows


def per_query(function, queries):
    """Median seconds of function(query) over the queries."""
    times = []
    for query in queries:
        start = time.perf_counter()
        function(query)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--entries", type=int, default=20000)
    parser.add_argument("--queries", type=int, default=300)
    parser.add_argument("--words", type=int, default=300)
    arguments = parser.parse_args()
    import distributed

    vocabulary = binbow.Vocabulary.default("orb")
    entries = synthetic_bows(vocabulary, arguments.entries, arguments.words, 1)
    # Queries: half the words of an entry plus random ones, so they have real matches.
    rng = np.random.default_rng(2)
    queries = []
    for i in range(arguments.queries):
        words = np.union1d(entries[(i * 7) % len(entries)].words[::2],
                           rng.integers(0, vocabulary.word_count, size=arguments.words // 2))
        values = rng.random(len(words)).astype(np.float32)
        queries.append(binbow.BowVector(words.astype(np.uint32), values / values.sum()))

    single = binbow.Database(vocabulary)
    for bow in entries:
        single.add_bow(bow)
    local_time = per_query(lambda q: single.query(q, 10), queries)
    answer = single.query(queries[0], 10)
    pickling = per_query(lambda q: pickle.loads(pickle.dumps(q)), queries) + \
        per_query(lambda _: pickle.loads(pickle.dumps(answer)), queries[:50])
    print(f"synthetic: {arguments.entries} entries of ~{arguments.words} words, "
          f"{len(queries)} queries, top 10, vocabulary {vocabulary.word_count} words")
    print(f"one Database in this process: {local_time * 1e3:.2f} ms/query "
          f"({1 / local_time:.0f} queries/s)")
    print(f"pickling one query and one answer (each way): {pickling * 1e3:.3f} ms")
    print("| worker processes | shards | queries/s | ms/query | shards compute (ms) "
          "| merge (ms) | pickling (ms) | Dask messages (ms) | empty call to every shard (ms) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for workers in (1, 2):
        with distributed.LocalCluster(n_workers=workers, processes=True, threads_per_worker=1,
                                      dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            for shards in (1, 2, 4):
                sharded = ShardedDatabase(client, vocabulary, shards=shards)
                for start in range(0, len(entries), 5000):
                    sharded.add_many(entries[start:start + 5000])
                assert sharded.query(queries[0], 10) == single.query(queries[0], 10)
                total = per_query(lambda q: sharded.query(q, 10), queries)
                # The shards' own compute: a Database of 1/shards of the entries
                # here; a worker runs its shards one after the other.
                part = binbow.Database(vocabulary)
                for bow in entries[::shards]:
                    part.add_bow(bow)
                shard_time = per_query(lambda q: part.query(q, 10), queries)
                compute = shard_time * -(-shards // workers)
                answers = [single.query(queries[0], 10) for _ in range(shards)]
                merge = per_query(
                    lambda _: sorted((r for a in answers for r in a),
                                     key=lambda r: (-r[1], r[0]))[:10], queries)
                serial = pickling * shards
                rest = max(0.0, total - compute - merge - serial)
                # Measured directly: a call that does nothing on every shard (len()).
                empty = per_query(lambda _: len(sharded), queries)
                print(f"| {workers} | {shards} | {1 / total:.0f} | {total * 1e3:.2f} | "
                      f"{compute * 1e3:.2f} | {merge * 1e3:.3f} | {serial * 1e3:.3f} | "
                      f"{rest * 1e3:.2f} | {empty * 1e3:.2f} |")
                del sharded


if __name__ == "__main__":
    main()
