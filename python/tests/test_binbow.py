"""Tests of the Python module against brute force, on random descriptors."""
import os
import tempfile
import threading
import unittest

import numpy as np

import binbow


def clustered(rng, rows, centers=50, noise=0.08, code_size=32):
    base = rng.integers(0, 256, size=(centers, code_size), dtype=np.uint8)
    picked = base[rng.integers(0, centers, size=rows)]
    bits = np.unpackbits(picked, axis=1)
    flips = rng.random(bits.shape) < noise
    return np.packbits(bits ^ flips, axis=1)


class VocabularyTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.rng = np.random.default_rng(1)
        cls.images = [clustered(cls.rng, 300) for _ in range(12)]
        cls.voc = binbow.Vocabulary.build(cls.images, branching=5, levels=3, seed=3)

    def test_hamming_matches_numpy(self):
        a, b = self.images[0][0], self.images[0][1]
        expected = int(np.unpackbits(a ^ b).sum())
        self.assertEqual(binbow.hamming(a, b), expected)

    def test_build_is_deterministic_and_describes_itself(self):
        again = binbow.Vocabulary.build(self.images, branching=5, levels=3, seed=3, threads=1)
        self.assertEqual(again.word_count, self.voc.word_count)
        self.assertEqual(self.voc.branching, 5)
        self.assertEqual(self.voc.code_size, 32)
        self.assertEqual(self.voc.weighting, "tf-idf")
        self.assertIn("k=5 L=3", repr(self.voc))

    def test_transform_is_sorted_normalised_and_consistent_with_quantize(self):
        bow = self.voc.transform(self.images[0])
        words = bow.words
        self.assertTrue(np.all(np.diff(words.astype(np.int64)) > 0))
        self.assertAlmostEqual(float(np.abs(bow.values).sum()), 1.0, places=5)
        quantized = set(self.voc.quantize(self.images[0]).tolist())
        self.assertTrue(set(words.tolist()) <= quantized)
        self.assertAlmostEqual(self.voc.score(bow, bow), 1.0, places=5)

    def test_feature_vector_covers_every_feature(self):
        _, fv = self.voc.transform_with_features(self.images[1], levels_up=1)
        covered = sorted(i for indices in fv.values() for i in indices.tolist())
        self.assertLessEqual(len(covered), len(self.images[1]))
        self.assertEqual(len(covered), len(set(covered)))

    def test_save_load_round_trip(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "v.bbw")
            self.voc.save(path)
            loaded = binbow.Vocabulary.load(path)
            self.assertEqual(loaded.transform(self.images[2]), self.voc.transform(self.images[2]))

    def test_records_the_descriptor_it_was_trained_on(self):
        self.assertEqual(self.voc.descriptor, "")
        orb = binbow.Vocabulary.build(self.images, branching=5, levels=2, descriptor="orb")
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "orb.bbw")
            orb.save(path)
            self.assertEqual(binbow.Vocabulary.load(path).descriptor, "orb")
        with self.assertRaises(ValueError):
            binbow.Vocabulary.build(self.images, branching=5, levels=2, descriptor="ORB!")

    def test_errors_are_python_exceptions(self):
        with self.assertRaises(OSError):
            binbow.Vocabulary.load("/nonexistent/v.bbw")
        with self.assertRaises(ValueError):
            self.voc.transform(np.zeros((3, 64), dtype=np.uint8))
        with self.assertRaises(ValueError):
            self.voc.transform(np.zeros(32, dtype=np.uint8))


class DatabaseTest(unittest.TestCase):
    def test_query_equals_brute_force_and_remove(self):
        rng = np.random.default_rng(2)
        images = [clustered(rng, 200) for _ in range(30)]
        voc = binbow.Vocabulary.build(images[:10], branching=6, levels=3, seed=1)
        db = binbow.Database(voc)
        for image in images:
            db.add(image)
        self.assertEqual(len(db), 30)
        query = voc.transform(images[7])
        results = db.query(query, max_results=5)
        bows = [voc.transform(image) for image in images]
        brute = sorted(((-voc.score(query, b), i) for i, b in enumerate(bows)))[:5]
        self.assertEqual([r[0] for r in results], [i for _, i in brute])
        for (entry, score, shared), (negative, _) in zip(results, brute):
            self.assertAlmostEqual(score, -negative, places=5)
        db.remove(7)
        self.assertNotIn(7, [r[0] for r in db.query(query, max_results=30)])
        self.assertNotIn(7, db)

    def test_queries_run_in_parallel_threads(self):
        rng = np.random.default_rng(3)
        images = [clustered(rng, 200) for _ in range(20)]
        voc = binbow.Vocabulary.build(images, branching=6, levels=3, seed=1)
        db = binbow.Database(voc)
        for image in images:
            db.add(image)
        bows = [voc.transform(image) for image in images]
        expected = [db.query(b, 3) for b in bows]
        results = [None] * len(bows)

        def work(i):
            results[i] = db.query(bows[i], 3)

        threads = [threading.Thread(target=work, args=(i,)) for i in range(len(bows))]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        self.assertEqual(results, expected)


if __name__ == "__main__":
    unittest.main()
