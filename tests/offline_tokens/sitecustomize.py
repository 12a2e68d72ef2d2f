"""Loaded at start-up by the Python processes a test runs with this folder on PYTHONPATH.

inspect's mockllm counts the tokens of its default output with tiktoken's ``o200k_base``
vocabulary, which tiktoken downloads on first use. Where that download cannot happen (an
offline CI machine), this registers a byte-level stand-in under the same name, so token counts
are estimates (one token a byte) instead of every model turn failing. Where the real
vocabulary loads (online, or cached in TIKTOKEN_CACHE_DIR), nothing changes.
"""

from __future__ import annotations


def _register_stand_in() -> None:
    try:
        import tiktoken
        from tiktoken import registry
    except ImportError:
        return
    try:
        tiktoken.get_encoding("o200k_base")
    except Exception:  # no network and no cached vocabulary
        registry.ENCODINGS["o200k_base"] = tiktoken.Encoding(
            name="o200k_base", pat_str=r"\S+|\s+",
            mergeable_ranks={bytes([b]): b for b in range(256)}, special_tokens={})


_register_stand_in()
