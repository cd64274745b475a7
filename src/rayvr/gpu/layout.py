"""Buffer record layouts declared once: a `Record` of `Field`s gives both the GLSL struct text and
the numpy structured dtype that packs it, with the std430 or std140 offsets.

The rules are the GL 4.5 specification's (section 7.6.2.2): a scalar aligns to 4 bytes, a vec2
to 8, a vec3 and a vec4 to 16 (a vec3 takes 12 bytes, so a scalar after it fills its fourth slot);
an array's elements and a matrix's columns are strided by their alignment (std140 rounds the
stride up to 16); a struct aligns to its widest member (std140: at least 16) and its size rounds
up to that. Where the layout pads an array element or a matrix column, the dtype keeps the padding
as trailing components: a std430 `vec3 a[2]` is a (2, 4) float32 field, a `mat3` is (3, 4),
indexed [column, row] as GLSL's column-major matrices are.
"""
from __future__ import annotations

import dataclasses

import numpy as np

_SCALARS = {"float": "<f4", "int": "<i4", "uint": "<u4"}
_VECTOR_PREFIX = {"": "float", "i": "int", "u": "uint"}
LAYOUTS = ("std430", "std140")


def _shape(glsl_type: str) -> tuple[str, int, int]:
    """(scalar, components per column, columns) of a GLSL scalar, vector or square matrix type."""
    if glsl_type in _SCALARS:
        return glsl_type, 1, 1
    for prefix, scalar in _VECTOR_PREFIX.items():
        if glsl_type.startswith(prefix + "vec") and glsl_type[len(prefix) + 3:] in ("2", "3", "4"):
            return scalar, int(glsl_type[-1]), 1
    if glsl_type in ("mat2", "mat3", "mat4"):
        n = int(glsl_type[-1])
        return "float", n, n
    raise ValueError(f"record field type {glsl_type!r}: use a scalar, vector or matN of {', '.join(_SCALARS)}")


def _round_up(x: int, to: int) -> int:
    return (x + to - 1) // to * to


@dataclasses.dataclass(frozen=True)
class Field:
    """One member of a record: its name, GLSL type, array length (0: not an array), meaning."""

    name: str
    type: str
    count: int = 0
    meaning: str = ""


@dataclasses.dataclass(frozen=True)
class _Placed:
    field: Field
    offset: int
    size: int
    alignment: int
    dtype: object


def _place(f: Field, layout: str, offset: int) -> _Placed:
    scalar, rows, columns = _shape(f.type)
    vector_align = 4 * (4 if rows == 3 else rows)
    if f.count == 0 and columns == 1:   # a scalar or a vector
        align, size = vector_align, 4 * rows
        dtype = np.dtype(_SCALARS[scalar]) if rows == 1 else np.dtype((_SCALARS[scalar], (rows,)))
    else:   # an array or a matrix: elements (or columns) at a stride
        stride = _round_up(vector_align, 16) if layout == "std140" else vector_align
        align = stride
        if columns > 1:   # a matrix: `columns` columns of `rows` floats
            element_shape = (columns, stride // 4)
            element = stride * columns
        else:
            element_shape = (stride // 4,) if stride // 4 > 1 else ()
            element = stride
        shape = ((f.count,) if f.count else ()) + element_shape
        size = element * max(f.count, 1)
        dtype = np.dtype((_SCALARS[scalar], shape)) if shape else np.dtype(_SCALARS[scalar])
    offset = _round_up(offset, align)
    return _Placed(f, offset, size, align, dtype)


class Record:
    """A struct in a buffer: its fields in order, their offsets in `layout` ("std430", "std140"),
    the GLSL struct (`glsl()`) and the numpy dtype of one record (`dtype`, `zeros(n)`)."""

    def __init__(self, name: str, fields, layout: str = "std430", meaning: str = ""):
        if layout not in LAYOUTS:
            raise ValueError(f"record {name}: layout {layout!r}; use one of {LAYOUTS}")
        names = [f.name for f in fields]
        if len(set(names)) != len(names):
            raise ValueError(f"record {name}: a field name repeats in {names}")
        self.name, self.layout, self.meaning = name, layout, meaning
        self.fields = tuple(fields)
        placed, offset = [], 0
        for f in self.fields:
            p = _place(f, layout, offset)
            placed.append(p)
            offset = p.offset + p.size
        self._placed = {p.field.name: p for p in placed}
        self.alignment = max((p.alignment for p in placed), default=4)
        if layout == "std140":
            self.alignment = _round_up(self.alignment, 16)
        self.size = _round_up(offset, self.alignment)
        self.dtype = np.dtype({"names": names, "formats": [p.dtype for p in placed],
                               "offsets": [p.offset for p in placed], "itemsize": self.size})

    def offset(self, name: str) -> int:
        """Byte offset of field `name` in a record."""
        try:
            return self._placed[name].offset
        except KeyError:
            raise KeyError(f"record {self.name} has no field {name!r}; fields: "
                           f"{', '.join(self._placed)}") from None

    def zeros(self, n: int) -> np.ndarray:
        """n zeroed records, as a structured array whose bytes are the buffer's."""
        return np.zeros(n, self.dtype)

    def glsl(self) -> str:
        """The GLSL struct declaration, a field a line with its meaning as a comment."""
        lines = [f"// {self.meaning}"] if self.meaning else []
        lines.append(f"struct {self.name} {{")
        for f in self.fields:
            decl = f"    {f.type} {f.name}{f'[{f.count}]' if f.count else ''};"
            lines.append(f"{decl}{' ' * max(1, 26 - len(decl))}// {f.meaning}" if f.meaning else decl)
        lines.append("};")
        return "\n".join(lines)
