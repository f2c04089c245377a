#!/usr/bin/python3
"""tools/kernel-vm/resolve against archive states that have happened (tests/tools/archive/).

kernel_resolve_test.py SOURCE_DIR [TestCase.test_name ...]: each case names the set it must
resolve to, package by package, or what it must refuse with; and tools/quickstart.sh must pick
the compiler package the resolver picks. Needs Debian's python3-apt (the quickstart installs
it); no network, no root.
"""
import importlib.machinery
import importlib.util
import os
import re
import subprocess
import sys
import tempfile
import unittest

SOURCE = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else os.getcwd()
ARCHIVE = os.path.join(SOURCE, "tests/tools/archive")


def load_resolver():
    path = os.path.join(SOURCE, "tools/kernel-vm/resolve")
    loader = importlib.machinery.SourceFileLoader("kernel_vm_resolve", path)
    spec = importlib.util.spec_from_loader(loader.name, loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


resolver = load_resolver()


def state(name, drop=()):
    """A recorded archive state, less the (package, version-pattern) pairs in drop."""
    with open(os.path.join(ARCHIVE, name), encoding="utf-8") as f:
        stanzas = resolver.read_stanzas(f.read())
    for package, pattern in drop:
        stanzas[package] = [(v, d) for v, d in stanzas.get(package, [])
                            if not re.fullmatch(pattern, v)]
    return resolver.Archive(stanzas)


def resolve(archive, flavour="amd64"):
    chosen, notes = resolver.resolve(archive, flavour)
    return {role: (name, version) for role, name, version, _ in chosen}, notes


def bookworm_set(abi, version, kbuild, source, compiler_version, rt=False):
    flavour = "rt-amd64" if rt else "amd64"
    return {
        "kernel": (f"6.1.0-{abi}-{flavour}", version),
        "image": (f"linux-image-6.1.0-{abi}-{flavour}", version),
        "headers": (f"linux-headers-6.1.0-{abi}-{flavour}", version),
        "common": (f"linux-headers-6.1.0-{abi}-common" + ("-rt" if rt else ""), version),
        "kbuild": ("linux-kbuild-6.1", kbuild),
        "compiler": ("linux-compiler-gcc-12-x86", compiler_version),
        "source": ("linux-source-6.1", source),
    }


def trixie_set(abi, version, rt=False):
    flavour = "rt-amd64" if rt else "amd64"
    return {
        "kernel": (f"{abi}-{flavour}", version),
        "image": (f"linux-image-{abi}-{flavour}", version),
        "headers": (f"linux-headers-{abi}-{flavour}", version),
        "common": (f"linux-headers-{abi}-common" + ("-rt" if rt else ""), version),
        "kbuild": (f"linux-kbuild-{abi}", version),
        "compiler": ("gcc-14", "14.2.0-19"),
        "source": ("linux-source-6.12", version),
    }


class Resolve(unittest.TestCase):
    maxDiff = None

    # (a) Debian 12 on 2026-11-28: kbuild and the source a Debian revision ahead of the image.
    def test_kbuild_and_source_a_revision_ahead_of_the_image(self):
        chosen, notes = resolve(state("bookworm-2026-11-28.txt"))
        self.assertEqual(chosen, bookworm_set(56, "6.1.192-2", kbuild="6.1.192-3",
                                              source="6.1.192-3", compiler_version="6.1.192-3"))
        self.assertEqual(notes, [])

    def test_rt_flavour_on_debian_12_takes_the_common_rt_headers(self):
        chosen, _ = resolve(state("bookworm-2026-11-28.txt"), "rt-amd64")
        self.assertEqual(chosen, bookworm_set(56, "6.1.192-2", kbuild="6.1.192-3",
                                              source="6.1.192-3", compiler_version="6.1.192-3",
                                              rt=True))

    # (b) Superseded ABIs listed beside the current one: ABI 55 (older, complete) and ABI 57
    # (newer headers, no signed image yet) are not what linux-image-amd64 depends on.
    def test_superseded_abi_still_listed_is_not_chosen(self):
        chosen, _ = resolve(state("bookworm-2026-11-28.txt"))
        self.assertEqual(chosen["kernel"], ("6.1.0-56-amd64", "6.1.192-2"))

    def test_metapackage_moved_to_a_new_abi_old_one_still_listed(self):
        # Debian 13: each upload has its own ABI; 6.12.117's is still in trixie.
        chosen, notes = resolve(state("trixie-2026-11-28.txt"))
        self.assertEqual(chosen["kernel"], ("6.12.118+deb13-amd64", "6.12.118-1"))
        self.assertEqual(notes, [])

    def test_metapackage_moved_to_a_new_abi_old_one_gone(self):
        gone = [(p, r"6\.12\.117-1") for p in (
            "linux-image-amd64", "linux-image-6.12.117+deb13-amd64",
            "linux-headers-6.12.117+deb13-amd64", "linux-headers-6.12.117+deb13-common",
            "linux-kbuild-6.12.117+deb13", "linux-source-6.12")]
        chosen, _ = resolve(state("trixie-2026-11-28.txt", drop=gone))
        self.assertEqual(chosen, trixie_set("6.12.118+deb13", "6.12.118-1"))

    def test_new_abi_without_its_headers_falls_back_to_the_previous_complete_set(self):
        chosen, notes = resolve(state("bookworm-headers-lag-2024-04.txt"))
        self.assertEqual(chosen, bookworm_set(20, "6.1.85-1", kbuild="6.1.85-1",
                                              source="6.1.85-1", compiler_version="6.1.85-1"))
        self.assertEqual(len(notes), 1)
        self.assertIn("linux-image-amd64 6.1.90-1's set is incomplete", notes[0])
        self.assertIn("linux-headers-6.1.0-21-amd64 (= 6.1.90-1): the archive has none",
                      notes[0])

    def test_new_abi_without_its_headers_and_the_old_one_gone_names_what_is_missing(self):
        gone = [("linux-image-amd64", r"6\.1\.85-1"), ("linux-image-6.1.0-20-amd64", ".*")]
        with self.assertRaises(resolver.Unusable) as refused:
            resolve(state("bookworm-headers-lag-2024-04.txt", drop=gone))
        self.assertEqual(refused.exception.args[0], [
            "linux-image-amd64 6.1.90-1 depends on linux-image-6.1.0-21-amd64 (= 6.1.90-1); "
            "the archive does not offer its set:",
            "  linux-headers-6.1.0-21-amd64 (= 6.1.90-1): the archive has none"])

    def test_kbuild_older_than_the_headers_want_is_refused_with_what_the_archive_has(self):
        gone = [("linux-kbuild-6.1", r"6\.1\.192-3"), ("linux-image-amd64", r"6\.1\.176-1")]
        with self.assertRaises(resolver.Unusable) as refused:
            resolve(state("bookworm-2026-11-28.txt", drop=gone))
        self.assertIn("  linux-kbuild-6.1 (>= 6.1.192-2): the archive has 6.1.176-1",
                      refused.exception.args[0])

    def test_an_image_the_archive_no_longer_offers_is_named(self):
        gone = [("linux-image-6.1.0-56-amd64", ".*"), ("linux-image-amd64", r"6\.1\.176-1")]
        with self.assertRaises(resolver.Unusable) as refused:
            resolve(state("bookworm-2026-11-28.txt", drop=gone))
        self.assertIn("  linux-image-6.1.0-56-amd64 (= 6.1.192-2): the archive has none",
                      refused.exception.args[0])

    # The source: the image's own upstream release, its newest Debian revision; never another
    # upstream release (gpiolib.h's structures must be the kernel's).
    def test_source_of_another_upstream_release_is_refused(self):
        gone = [("linux-source-6.1", r"6\.1\.192-.*"), ("linux-image-amd64", r"6\.1\.176-1")]
        with self.assertRaises(resolver.Unusable) as refused:
            resolve(state("bookworm-2026-11-28.txt", drop=gone))
        self.assertIn("  linux-source-6.1 (6.1.192-*, the image's upstream release): the archive "
                      "has 6.1.190-1, 6.1.187-1, 6.1.176-1, 6.1.170-3", refused.exception.args[0])

    def test_source_missing_falls_back_to_an_older_complete_set(self):
        chosen, notes = resolve(state("bookworm-2026-11-28.txt",
                                      drop=[("linux-source-6.1", r"6\.1\.192-.*")]))
        self.assertEqual(chosen, bookworm_set(50, "6.1.176-1", kbuild="6.1.192-3",
                                              source="6.1.176-1", compiler_version="6.1.192-3"))
        self.assertIn("linux-source-6.1 (6.1.192-*", notes[0])

    # (c) apt's lists older than the archive: they resolve to what they record (the download
    # then fails and setup refreshes them: tests/tools/kernel_fetch_test).
    def test_stale_lists_resolve_to_the_set_they_record(self):
        chosen, _ = resolve(state("bookworm-lists-of-6.1.192-1.txt"))
        self.assertEqual(chosen, bookworm_set(55, "6.1.192-1", kbuild="6.1.192-1",
                                              source="6.1.192-1", compiler_version="6.1.192-1"))

    # (d) The ordinary case: one version everywhere; the older upstream's source is not taken.
    def test_everything_at_one_version(self):
        for rt in (False, True):
            chosen, notes = resolve(state("bookworm-main-6.1.176.txt"),
                                    "rt-amd64" if rt else "amd64")
            self.assertEqual(chosen, bookworm_set(50, "6.1.176-1", kbuild="6.1.176-1",
                                                  source="6.1.176-1",
                                                  compiler_version="6.1.176-1", rt=rt))
            self.assertEqual(notes, [])

    # (e) Debian 13: 6.12, per-ABI kbuild with an unversioned dependency, gcc-14 as the
    # compiler, the headers also depending on their image.
    def test_debian_13(self):
        chosen, _ = resolve(state("trixie-2026-11-28.txt"))
        self.assertEqual(chosen, trixie_set("6.12.118+deb13", "6.12.118-1"))

    def test_rt_flavour_on_debian_13_takes_the_common_rt_headers(self):
        chosen, _ = resolve(state("trixie-2026-11-28.txt"), "rt-amd64")
        self.assertEqual(chosen, trixie_set("6.12.118+deb13", "6.12.118-1", rt=True))

    def test_no_lists_at_all(self):
        with self.assertRaises(resolver.Unusable) as refused:
            resolve(resolver.Archive({}))
        self.assertIn("apt knows no linux-image-amd64", refused.exception.args[0][0])

    # Debian's version order, not the strings': -10 after -9, ~ before anything.
    def test_versions_are_compared_as_debian_compares_them(self):
        text = """
Package: linux-image-amd64
Version: 6.12.22-1~bpo12+1
Depends: linux-image-6.12.22+bpo-amd64 (= 6.12.22-1~bpo12+1)

Package: linux-image-6.12.22+bpo-amd64
Version: 6.12.22-1~bpo12+1

Package: linux-headers-6.12.22+bpo-amd64
Version: 6.12.22-1~bpo12+1
Depends: linux-headers-6.12.22+bpo-common (= 6.12.22-1~bpo12+1), linux-kbuild-6.12.22+bpo (>= 6.12.22-1~bpo12+1), gcc-14

Package: linux-headers-6.12.22+bpo-common
Version: 6.12.22-1~bpo12+1

Package: linux-kbuild-6.12.22+bpo
Version: 6.12.22-1~bpo12+1

Package: linux-kbuild-6.12.22+bpo
Version: 6.12.22-1~bpo12+0

Package: gcc-14
Version: 14.2.0-19

Package: linux-source-6.12
Version: 6.12.22-9

Package: linux-source-6.12
Version: 6.12.22-10

Package: linux-source-6.12
Version: 6.12.22-1~bpo12+1
"""
        chosen, _ = resolve(resolver.Archive(resolver.read_stanzas(text)))
        self.assertEqual(chosen["kbuild"], ("linux-kbuild-6.12.22+bpo", "6.12.22-1~bpo12+1"))
        self.assertEqual(chosen["source"], ("linux-source-6.12", "6.12.22-10"))

    # Live, apt-cache show also prints installed packages no archive offers: no Filename.
    def test_installed_records_without_filename_are_not_offered(self):
        text = ("Package: linux-kbuild-6.1\nVersion: 6.1.192-2\n\n"
                "Package: linux-kbuild-6.1\nVersion: 6.1.192-3\n"
                "Filename: pool/updates/main/l/linux/linux-kbuild-6.1_6.1.192-3_amd64.deb\n")
        self.assertEqual(resolver.read_stanzas(text, downloadable_only=True),
                         {"linux-kbuild-6.1": [("6.1.192-3", "")]})
        self.assertEqual(len(resolver.read_stanzas(text)["linux-kbuild-6.1"]), 2)


class QuickstartAgrees(unittest.TestCase):
    """tools/quickstart.sh installs the compiler package the resolver's headers depend on: its
    release_packages, run over the same archive state through tests/tools/fake-apt."""

    def quickstart_compiler(self, fixture, flavour):
        with open(os.path.join(SOURCE, "tools/quickstart.sh"), encoding="utf-8") as f:
            script = f.read()
        function = re.search(r"^release_packages\(\) \{\n.*?^\}\n", script, re.S | re.M)
        self.assertIsNotNone(function, "tools/quickstart.sh has no release_packages()")
        with tempfile.TemporaryDirectory() as tmp:
            bindir = os.path.join(tmp, "bin")
            os.mkdir(bindir)
            for tool in ("apt-cache", "apt-get"):
                os.symlink(os.path.join(SOURCE, "tests/tools/fake-apt"),
                           os.path.join(bindir, tool))
            with open(os.path.join(ARCHIVE, fixture), encoding="utf-8") as src, \
                    open(os.path.join(tmp, "lists"), "w", encoding="utf-8") as dst:
                dst.write(src.read())
            env = dict(os.environ, PATH=f"{bindir}:{os.environ['PATH']}", FAKE_APT_DIR=tmp,
                       XDG_CACHE_HOME=os.path.join(tmp, "cache"), HAPTICD_KERNEL_FLAVOUR=flavour)
            out = subprocess.run(["bash", "-c", function.group(0) + "release_packages"],
                                 env=env, stdout=subprocess.PIPE, text=True, check=True).stdout
        return out.split()

    def test_same_compiler_package(self):
        cases = [("bookworm-2026-11-28.txt", "amd64"), ("bookworm-2026-11-28.txt", "rt-amd64"),
                 ("bookworm-main-6.1.176.txt", "amd64"), ("trixie-2026-11-28.txt", "amd64"),
                 ("trixie-2026-11-28.txt", "rt-amd64")]
        for fixture, flavour in cases:
            with self.subTest(fixture=fixture, flavour=flavour):
                chosen, _ = resolve(state(fixture), flavour)
                names = self.quickstart_compiler(fixture, flavour)
                self.assertEqual(names[1:], [chosen["compiler"][0]])
        self.assertEqual(self.quickstart_compiler("trixie-2026-11-28.txt", "amd64"),
                         ["libclang-rt-19-dev", "gcc-14"])


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v", *sys.argv[2:]])
