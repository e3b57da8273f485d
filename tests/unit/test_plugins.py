"""The generic registry: built-ins, entry-point plugins (installed into a temporary folder), runtime
registrations, and what happens when they clash or break."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from snakebot.errors import SnakebotError
from snakebot.plugins import PluginWarning, Registry
from tests.plugins.install import on_path, write_dist_info, write_module

GROUP = "snakebot.test_factories"
Factory = Callable[[], str]


class FactoryError(SnakebotError):
    """The domain error of the test registry."""


def check(name: str, obj: object) -> Factory:
    if not callable(obj):
        raise TypeError(f"expected a factory (a callable), got {type(obj).__name__}")
    return obj


def make(**builtins: Factory | str) -> Registry[Factory]:
    return Registry("factory", GROUP, error=FactoryError, check=check, builtins=builtins)


def sim() -> str:
    return "sim"


@pytest.fixture
def site(tmp_path: Path) -> Iterator[Path]:
    folder = tmp_path / "site"
    folder.mkdir()
    with on_path(folder):
        yield folder


def plugin(site: Path, dist: str, version: str, points: dict[str, str], **modules: str) -> None:
    for name, source in modules.items():
        write_module(site, name, source)
    write_dist_info(site, dist, version, {GROUP: points})


def test_builtins_are_found_by_name_and_a_reference_is_imported_on_first_use(site: Path) -> None:
    write_module(site, "lazy_builtin", "def make():\n    return 'lazy'\n")
    registry = make(sim=sim, lazy="lazy_builtin:make")
    assert registry.names() == ["lazy", "sim"] and "sim" in registry
    assert "lazy_builtin" not in sys.modules
    assert registry.get("lazy")() == "lazy" and "lazy_builtin" in sys.modules
    assert registry.get("sim") is sim
    assert str(registry.origin("sim")) == "built-in"


def test_an_unknown_name_raises_the_domain_error_with_a_hint_and_the_known_names() -> None:
    registry = make(sim=sim, dynamixel=sim)
    with pytest.raises(FactoryError, match=r"unknown factory 'simm' \(did you mean 'sim'\?\); "):
        registry.get("simm")
    with pytest.raises(FactoryError, match="known factorys: dynamixel, sim"):
        registry.origin("nothing like it")


def test_a_plugin_is_found_through_its_entry_point_and_imported_only_when_used(
    site: Path,
) -> None:
    plugin(
        site,
        "demo-plugin",
        "1.2",
        {"demo": "demo_factories:make"},
        demo_factories="def make():\n    return 'demo'\n",
    )
    registry = make(sim=sim)
    assert registry.names() == ["demo", "sim"]
    origin = registry.origin("demo")
    assert str(origin) == "plugin demo-plugin 1.2"
    assert origin.entry_point == "demo = demo_factories:make"
    assert "demo_factories" not in sys.modules
    assert registry.get("demo")() == "demo"


def test_a_plugin_that_fails_to_import_breaks_only_its_own_entry(site: Path) -> None:
    plugin(
        site,
        "broken-plugin",
        "0.3",
        {"broken": "broken_factories:make"},
        broken_factories="import a_module_nobody_installed\n",
    )
    plugin(site, "fine-plugin", "1.0", {"fine": "fine_factories:make"}, fine_factories="make = str")
    registry = make(sim=sim)
    assert "broken" in registry.names()
    with pytest.warns(PluginWarning) as caught:
        loaded = registry.load_all()
    assert sorted(loaded) == ["fine", "sim"]
    (warning,) = caught
    message = str(warning.message)
    assert "broken-plugin 0.3" in message and "broken = broken_factories:make" in message
    assert "ModuleNotFoundError" in message and "a_module_nobody_installed" in message
    with pytest.raises(FactoryError, match=r"'broken' from plugin broken-plugin 0\.3 .*failed"):
        registry.get("broken")
    assert registry.get("fine")() == ""


def test_a_plugin_object_that_fails_the_check_is_reported_like_an_import_failure(
    site: Path,
) -> None:
    plugin(site, "odd-plugin", "2.0", {"odd": "odd_factories:VALUE"}, odd_factories="VALUE = 3")
    with pytest.raises(FactoryError, match=r"odd-plugin 2\.0.*TypeError: expected a factory"):
        make().get("odd")


def test_a_plugin_cannot_take_a_builtin_name(site: Path) -> None:
    plugin(site, "sneaky-plugin", "0.1", {"sim": "sneaky:make"}, sneaky="make = str")
    registry = make(sim=sim)
    with pytest.warns(PluginWarning, match=r"plugin sneaky-plugin 0\.1 .*built-in is kept"):
        assert registry.get("sim") is sim
    assert str(registry.origin("sim")) == "built-in"


def test_two_plugins_with_one_name_are_both_refused_until_one_is_chosen(site: Path) -> None:
    plugin(site, "first-plugin", "1.0", {"twin2": "first:make"}, first="def make():\n  return 1")
    plugin(site, "second-plugin", "2.0", {"twin2": "second:make"}, second="make = str")
    registry = make(sim=sim)
    with pytest.warns(PluginWarning, match="first-plugin 1.0.*second-plugin 2.0|second.*first"):
        assert "twin2" in registry.names()
    with pytest.raises(FactoryError) as info:
        registry.get("twin2")
    assert "first-plugin 1.0" in str(info.value) and "second-plugin 2.0" in str(info.value)
    assert "first" not in sys.modules and "second" not in sys.modules
    assert sorted(registry.load_all()) == ["sim"]
    registry.register("twin2", "second:make", replace=True)
    assert registry.get("twin2")() == ""


def test_register_checks_at_once_refuses_taken_names_and_unregister_restores(site: Path) -> None:
    registry = make(sim=sim)
    with pytest.raises(FactoryError, match="cannot register factory 'bad': expected a factory"):
        registry.register("bad", 3)  # type: ignore[arg-type]
    with pytest.raises(FactoryError, match=r"'sim' is already registered \(built-in\)"):
        registry.register("sim", str)
    registry.register("mine", str)
    assert str(registry.origin("mine")) == "registered at runtime"
    with pytest.raises(FactoryError, match=r"already registered \(registered at runtime\)"):
        registry.register("mine", sim)
    registry.register("sim", str, replace=True)
    assert registry.get("sim") is str
    registry.unregister("sim")
    assert registry.get("sim") is sim
    with pytest.raises(FactoryError, match="only runtime registrations can be removed"):
        registry.unregister("sim")


def test_register_a_reference_imports_it_on_first_use(site: Path) -> None:
    write_module(site, "later_factories", "def make():\n    return 'later'\n")
    registry = make()
    registry.register("later", "later_factories:make")
    assert "later_factories" not in sys.modules
    assert registry.get("later")() == "later"
    with pytest.raises(FactoryError, match="expected an object or a 'module:attr' reference"):
        registry.register("nope", "not a reference")
    registry.register("gone", "no_such_module_here:make")
    with pytest.raises(FactoryError, match=r"registered at runtime .*ModuleNotFoundError"):
        registry.get("gone")


def test_refresh_finds_a_plugin_installed_after_the_first_lookup(site: Path) -> None:
    registry = make(sim=sim)
    assert registry.names() == ["sim"]
    plugin(site, "late-plugin", "1.0", {"late": "late:make"}, late="make = str")
    assert registry.names() == ["sim"]
    registry.refresh()
    assert registry.names() == ["late", "sim"]
