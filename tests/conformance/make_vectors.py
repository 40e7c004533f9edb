#!/usr/bin/python3
"""Generates (once) the canmatrix oracle's random test vectors for every DBC of the corpus.

    make_vectors.py --corpus KIT/corpus/dbc --oracle KIT/tools/dbc-oracle.py --cache DIR

For every *.dbc under --corpus (case-insensitive, recursive, sorted) runs
    dbc-oracle.py random DBC --n 20 --seed 1939 --out DIR/<key>.jsonl
where <key> is the sha1 of the DBC file plus the oracle options, so a vector file is made
once per corpus content and reused by later runs. Then writes DIR/index.tsv:
    <path relative to --corpus> TAB <sha1> TAB <vector file> TAB <oracle stderr, one line>
which the conformance test reads.

Exit status: 0 done; 77 canmatrix is not importable (the test then skips); 1 otherwise.
Runs the oracle in parallel (--jobs, default: CPU count); holds DIR/.lock so that
concurrent test processes generate each file only once.
"""
import argparse
import concurrent.futures
import contextlib
import fcntl
import hashlib
import io
import os
import subprocess
import sys

VECTORS_PER_MESSAGE = 20
SEED = 1939
SKIP = 77


def sha1_of(path):
    digest = hashlib.sha1()
    with open(path, "rb") as f:
        digest.update(f.read())
    return digest.hexdigest()


def generate(oracle, dbc, out):
    """Runs the oracle into out (via a temporary file, so a crash leaves no half file)."""
    tmp = out + ".tmp"
    proc = subprocess.run([sys.executable, oracle, "random", dbc, "--n", str(VECTORS_PER_MESSAGE),
                           "--seed", str(SEED), "--out", tmp],
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    note = " ".join(proc.stderr.split())
    if proc.returncode != 0:
        with open(tmp, "w") as f:  # an empty vector set, the failure kept as the note
            pass
        note = f"oracle exit {proc.returncode}: {note}"
    with open(out + ".note", "w") as f:
        f.write(note)
    os.replace(tmp, out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--corpus", required=True)
    ap.add_argument("--oracle", required=True)
    ap.add_argument("--cache", required=True)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    args = ap.parse_args()

    try:
        with contextlib.redirect_stdout(io.StringIO()):  # canmatrix lists the formats it lacks
            import canmatrix.formats.dbc  # noqa: F401
    except Exception as e:  # the test prints this and skips
        print(f"canmatrix is not importable by {sys.executable}: {type(e).__name__}: {e}")
        return SKIP

    os.makedirs(args.cache, exist_ok=True)
    with open(args.oracle, "rb") as f:
        oracle_key = hashlib.sha1(f.read()).hexdigest()[:12]
    files = []
    for root, _, names in os.walk(args.corpus):
        for name in names:
            if name.lower().endswith(".dbc"):
                files.append(os.path.relpath(os.path.join(root, name), args.corpus))
    files.sort()

    with open(os.path.join(args.cache, ".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        rows, todo = [], []
        for rel in files:
            sha1 = sha1_of(os.path.join(args.corpus, rel))
            out = os.path.join(args.cache, f"{sha1}-n{VECTORS_PER_MESSAGE}-s{SEED}-o{oracle_key}.jsonl")
            rows.append((rel, sha1, out))
            if not os.path.exists(out) and all(out != queued for _, queued in todo):  # identical files once
                todo.append((os.path.join(args.corpus, rel), out))
        if todo:
            print(f"generating canmatrix vectors for {len(todo)} of {len(files)} DBC files", file=sys.stderr)
            with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
                list(pool.map(lambda job: generate(args.oracle, *job), todo))
        with open(os.path.join(args.cache, "index.tsv.tmp"), "w") as index:
            for rel, sha1, out in rows:
                with open(out + ".note") as f:
                    note = f.read().replace("\t", " ").replace("\n", " ")
                index.write(f"{rel}\t{sha1}\t{out}\t{note}\n")
        os.replace(os.path.join(args.cache, "index.tsv.tmp"), os.path.join(args.cache, "index.tsv"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
