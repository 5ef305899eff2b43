"""Build hook: ship the repository's ``examples/`` in the wheel as ``kinprop/examples/``.

Everything else is in pyproject.toml. The example models stay in one place (``examples/``, the
paths the README uses); this copies them into the built package so an installed kinprop has
them (``kinprop paper``, ``kinprop.resources.examples_dir()``).
"""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
#: what an example is: models, scripts, other tools' files (examples/chrono, examples/mjcf) and their notes
SUFFIXES = (".yaml", ".yml", ".json", ".xml", ".py", ".md")


class BuildWithExamples(build_py):
    def run(self) -> None:
        super().run()
        if self.editable_mode:  # an editable install reads examples/ in place
            return
        target = Path(self.build_lib) / "kinprop" / "examples"
        target.mkdir(parents=True, exist_ok=True)
        for src in sorted((ROOT / "examples").rglob("*")):
            if src.suffix in SUFFIXES and src.is_file():
                dest = target / src.relative_to(ROOT / "examples")
                dest.parent.mkdir(parents=True, exist_ok=True)
                self.copy_file(str(src), str(dest))


setup(cmdclass={"build_py": BuildWithExamples})
