#!/usr/bin/env python3
"""The documents against the tree: every repository path a document names exists, every link's
anchor is a heading of its page, and every `netlab ...` command line a document shows parses.

Documents: README.md, docs/*.md and every README.md below the root. Checked in them:
- paths in backticks or links whose first part is a top-level folder of the repository
  (`common/tracks/track_file.h`, `docs/score.md`), and in a folder's README the bare source
  names it lists (`bench_file.h`), which are its own files; placeholders (`<case>`, `*`, `NAME`
  in capitals, `...`) are not paths. `build/bench/NAME` must be a benchmark bench/CMakeLists.txt
  declares; other build outputs are not checked.
- links to a page's heading (`docs/benchmarks.md#labeling`, `#the-implicit-integrator`): the
  heading exists (GitHub's anchors: lower case, punctuation dropped, spaces as '-'); and a
  section named by its heading, `docs/simulator.md, "The implicit integrator"`: a heading of
  that page, or a paragraph's bold lead-in, starts with those words.
- `netlab SUBCOMMAND ...` lines of code blocks, and inline code that starts so: the subcommand
  exists and each --flag is one its --help lists.

Usage: docs_test.py --root SOURCE_DIR --netlab PATH_TO_NETLAB. Prints one line per failure
(file:line: what) and exits 1 when there is any.
"""
import argparse
import os
import re
import shlex
import subprocess
import sys

SOURCE_SUFFIXES = (".h", ".cc", ".md", ".py", ".sh", ".txt", ".cmake")


def documents(root):
    docs = ["README.md"]
    docs += sorted("docs/" + f for f in os.listdir(os.path.join(root, "docs")) if f.endswith(".md"))
    for top in sorted(os.listdir(root)):
        if top.startswith(".") or top.startswith("build") or top == "docs":
            continue
        if not os.path.isdir(os.path.join(root, top)):
            continue
        for folder, dirs, files in os.walk(os.path.join(root, top)):
            dirs[:] = sorted(d for d in dirs if not d.startswith("."))
            if "README.md" in files:
                docs.append(os.path.relpath(os.path.join(folder, "README.md"), root))
    return docs


def top_level_folders(root):
    return {e for e in os.listdir(root)
            if os.path.isdir(os.path.join(root, e)) and not e.startswith(".") and
            not e.startswith("build")}


def benchmark_names(root):
    text = open(os.path.join(root, "bench", "CMakeLists.txt"), encoding="utf-8").read()
    return set(re.findall(r"^\s*netlab_add_bench\((\w+)", text, re.M))


def slug(heading):
    """GitHub's anchor of a heading."""
    text = re.sub(r"`", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        seen, result, in_code = {}, set(), False
        for line in open(path, encoding="utf-8"):
            if line.startswith("```"):
                in_code = not in_code
            m = None if in_code else re.match(r"#+\s+(.*)", line)
            if m:
                s = slug(m.group(1))
                n = seen.get(s, 0)
                result.add(s if n == 0 else "%s-%d" % (s, n))
                seen[s] = n + 1
        cache[path] = result
    return cache[path]


def headings(path, cache={}):
    """The headings of a page as text, lower case, without backticks."""
    if path not in cache:
        result, in_code = [], False
        for line in open(path, encoding="utf-8"):
            if line.startswith("```"):
                in_code = not in_code
            # A heading, or a paragraph's bold lead-in ("**The implicit integrator** (...)").
            m = None if in_code else (re.match(r"#+\s+(.*)", line) or
                                      re.match(r"(?:- )?\*\*([^*]+)\*\*", line))
            if m:
                result.append(m.group(1).replace("`", "").strip().rstrip(".").lower())
        cache[path] = result
    return cache[path]


def is_placeholder(token):
    return (any(c in token for c in "<>*{}$|…") or "..." in token or
            re.search(r"(^|/)[A-Z][A-Z_]+([./]|$)", token) is not None)


class Checker:
    def __init__(self, root, netlab):
        self.root, self.netlab = root, netlab
        self.tops = top_level_folders(root)
        self.benches = benchmark_names(root)
        self.helps = {}
        self.failures = []
        self.paths = self.commands = self.links = 0

    def fail(self, doc, line, what):
        self.failures.append("%s:%d: %s" % (doc, line, what))

    # --- paths -----------------------------------------------------------------------------
    def check_path(self, doc, line, token, from_link):
        token = token.strip()
        path, _, anchor = token.partition("#")
        path = re.sub(r":\d+(-\d+)?$", "", path)  # file.h:42
        path = re.sub(r"[),.;:]+$", "", path)
        if not path:
            if from_link and anchor:
                self.check_anchor(doc, line, doc, anchor)
            return
        if "://" in path or path.startswith("mailto:") or is_placeholder(path):
            return
        if not from_link and path.startswith(("/", "./", "../", "~")):
            return  # a dataset in a file (/knots/valid), a file outside the repository
        doc_dir = os.path.dirname(doc)
        first = path.split("/")[0]
        if first == "build":
            parts = path.split("/")
            if len(parts) >= 3 and parts[1] == "bench" and parts[2] not in self.benches:
                self.fail(doc, line, "`%s`: no benchmark %s in bench/CMakeLists.txt" %
                          (path, parts[2]))
            return
        candidates = []
        if from_link:
            candidates.append(os.path.normpath(os.path.join(doc_dir, path)))
        if first in self.tops:
            candidates.append(os.path.normpath(path))
        elif not from_link and doc_dir and doc_dir != "docs" and "/" not in path.rstrip("/") and \
                path.endswith(SOURCE_SUFFIXES) and os.path.basename(doc) == "README.md":
            candidates.append(os.path.normpath(os.path.join(doc_dir, path)))
        elif not from_link and "/" in path and os.path.isdir(os.path.join(self.root, doc_dir, first)) \
                and doc_dir:
            candidates.append(os.path.normpath(os.path.join(doc_dir, path)))
        if not candidates:
            return
        self.paths += 1
        for c in candidates:
            if c.startswith(".."):
                self.fail(doc, line, "`%s` is outside the repository" % token)
                return
            if os.path.exists(os.path.join(self.root, c)):
                if from_link and anchor and c.endswith(".md"):
                    self.check_anchor(doc, line, c, anchor)
                return
        self.fail(doc, line, "`%s` does not exist (looked for %s)" % (token, ", ".join(candidates)))

    def check_section(self, doc, line, target, section):
        """`docs/x.md, "Heading"`: a heading of that page starts with the quoted words."""
        path = os.path.join(self.root, target)
        if not os.path.isfile(path):
            return  # the path check reports it
        self.links += 1
        section = " ".join(section.split())
        want = section.replace("`", "").lower()
        if not any(h.startswith(want) for h in headings(path)):
            self.fail(doc, line, '%s, "%s": no heading of %s starts so' % (target, section, target))

    def check_anchor(self, doc, line, target, anchor):
        self.links += 1
        if anchor not in anchors(os.path.join(self.root, target)):
            self.fail(doc, line, "link to %s#%s: no such heading in %s" % (target, anchor, target))

    # --- command lines ---------------------------------------------------------------------
    def help_of(self, sub):
        if sub not in self.helps:
            try:
                r = subprocess.run([self.netlab, sub, "--help"], capture_output=True, text=True,
                                   timeout=60)
                self.helps[sub] = (r.returncode, r.stdout + r.stderr)
            except subprocess.TimeoutExpired:
                self.helps[sub] = (-1, "timed out")
        return self.helps[sub]

    def check_command(self, doc, line, text):
        try:
            words = shlex.split(text, comments=True)
        except ValueError as e:
            self.fail(doc, line, "`%s`: does not split into words (%s)" % (text, e))
            return
        for i, w in enumerate(words):  # one command: up to a pipe, a redirection or a chain
            if w in ("|", "||", "&&", ";", ">", ">>", "2>", "2>&1", "&") or w.startswith(">"):
                words = words[:i]
                break
        if len(words) < 2 or words[0] != "netlab":
            return
        sub = words[1]
        if not re.fullmatch(r"[a-z][a-z-]*", sub):
            return  # an option, a placeholder, or a message quoting the command ("netlab sweep:")
        self.commands += 1
        code, help_text = self.help_of(sub)
        if code != 0:
            self.fail(doc, line, "`%s`: netlab %s --help fails (exit %d): no such subcommand?" %
                      (text, sub, code))
            return
        listed = set(re.findall(r"(?<![\w-])(--[a-z0-9][a-z0-9-]*)", help_text))
        for w in words[2:]:
            if not w.startswith("--") or w == "--":
                continue
            flag = w.split("=", 1)[0]
            if flag not in listed:
                self.fail(doc, line, "`%s`: %s is not an option of netlab %s (its --help lists %s)"
                          % (text, flag, sub, " ".join(sorted(listed))))

    # --- a document ------------------------------------------------------------------------
    def check_document(self, doc):
        lines = open(os.path.join(self.root, doc), encoding="utf-8").read().split("\n")
        in_code, pending, pending_line = False, "", 0
        for n, raw in enumerate(lines, 1):
            if raw.lstrip().startswith("```"):
                in_code = not in_code
                continue
            if in_code:
                text = raw.strip()
                if pending:
                    text = pending + " " + text
                if text.endswith("\\"):
                    pending, pending_line = text[:-1], pending_line or n
                    continue
                start = pending_line or n
                pending, pending_line = "", 0
                text = re.sub(r"^\$\s+", "", text)
                # The executable by its path (build/app/netlab), or under mpirun.
                text = re.sub(r"^(?:mpirun\s+-np\s+\S+\s+)?(?:\S*/)netlab\s", "netlab ", text)
                text = re.sub(r"^mpirun\s+-np\s+\S+\s+netlab\s", "netlab ", text)
                if text.startswith("netlab "):
                    self.check_command(doc, start, text)
                for token in re.findall(r"(?<![\w/.-])((?:%s)/[\w./+-]*)" %
                                        "|".join(map(re.escape, sorted(self.tops | {"build"}))), text):
                    self.check_path(doc, start, token, from_link=False)
                continue
            for m in re.finditer(r"`([^`\n]+)`", raw):
                span = m.group(1).strip()
                if span.startswith("netlab "):
                    self.check_command(doc, n, span)
                    continue
                if " " in span:
                    continue
                self.check_path(doc, n, span, from_link=False)
            for m in re.finditer(r"\]\(([^)\s]+)\)", raw):
                self.check_path(doc, n, m.group(1), from_link=True)
        # Sections named by their heading: (docs/benchmarks.md, "Through the approach ...").
        text = "\n".join(lines)
        for m in re.finditer(r"`?((?:docs/)?[\w]+\.md)`?,\s+\"([^\"]+)\"", text):
            target = m.group(1)
            if "/" not in target:
                target = os.path.join(os.path.dirname(doc), target) if doc.startswith("docs/") \
                    else target
            self.check_section(doc, text.count("\n", 0, m.start()) + 1, target, m.group(2))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--root", required=True)
    parser.add_argument("--netlab", required=True)
    args = parser.parse_args()
    checker = Checker(os.path.abspath(args.root), args.netlab)
    docs = documents(checker.root)
    for doc in docs:
        checker.check_document(doc)
    for f in checker.failures:
        print(f)
    print("%d documents: %d paths, %d links and references to headings, %d netlab command lines (%d subcommands "
          "asked for --help): %d failures" % (len(docs), checker.paths, checker.links,
                                              checker.commands, len(checker.helps),
                                              len(checker.failures)))
    return 1 if checker.failures else 0


if __name__ == "__main__":
    sys.exit(main())
