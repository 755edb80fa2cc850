"""A campaign store's content, table by table, for the tests that compare two stores."""
import os
import sqlite3


def store_content(store, root=None, skip=()):
    """Every table's rows in key order; a text under `root` (a test's temporary folder) by its base
    name, so that two runs in two folders compare; tables in `skip` left out."""
    db = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    out = {}
    for (t,) in db.execute("SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name"):
        if t in skip:
            continue
        order = "key" if t == "meta" else "1, 2"
        rows = db.execute(f"SELECT * FROM {t} ORDER BY {order}").fetchall()
        out[t] = [tuple(os.path.basename(v) if root and isinstance(v, str) and v.startswith(root) else v for v in r)
                  for r in rows]
    db.close()
    return out
