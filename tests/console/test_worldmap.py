"""The console's text top view: every particle shown, the centroid marked, the lamp placed."""

from __future__ import annotations

from rich.text import Text

from particlebot.console.worldmap import MapParticle, render_map
from particlebot.protocol import State


def _lines(text: Text) -> list[str]:
    return str(text).splitlines()[:-1]  # (the last line is the scale)


def _styles_at(text: Text, char: str) -> list[str]:
    """The styles of every occurrence of `char` in the picture."""
    plain = str(text)
    found = []
    for span in text.spans:
        if plain[span.start : span.end] == char:
            found.append(str(span.style))
    return found


def test_a_particle_on_the_centroid_is_shown_reversed_not_hidden() -> None:
    # Three in a row: the middle one sits on the centroid.
    row = [MapParticle(i, 0.2 * i, 0.0, False, State.CYCLING) for i in (-1, 0, 1)]
    text = render_map(row, lamp=(-5.0, 0.0), track=[], width=41, height=11)
    picture = "".join(_lines(text))
    assert picture.count("O") == 3
    assert "+" not in picture
    assert sorted(s.endswith("reverse") for s in _styles_at(text, "O")) == [False, False, True]


def test_the_centroid_between_particles_is_a_plus() -> None:
    pair = [MapParticle(0, -0.3, 0.0, True, None), MapParticle(1, 0.3, 0.0, False, None)]
    text = render_map(pair, lamp=(-5.0, 0.0), track=[], width=41, height=11)
    lines = _lines(text)
    (middle,) = [line for line in lines if "+" in line]
    # The mark lies halfway between the two bodies, on their row.
    assert middle.index("+") * 2 == middle.index("@") + middle.index("O")
    assert not any("reverse" in s for s in _styles_at(text, "O") + _styles_at(text, "@"))


def test_a_lamp_beyond_the_frame_sits_on_its_edge_in_its_direction() -> None:
    pair = [MapParticle(0, -0.2, 0.0, False, None), MapParticle(1, 0.2, 0.0, False, None)]
    text = render_map(pair, lamp=(-50.0, 0.0), track=[], width=41, height=11)
    lines = _lines(text)
    (lamp_line,) = [line for line in lines if "*" in line]
    assert lamp_line.index("*") == 0  # the left edge, on the swarm's row
    assert "+" in lamp_line
    assert "lamp 50.00 m away" in str(text).splitlines()[-1]
