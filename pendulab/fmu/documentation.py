"""``documentation/index.html`` and the license file of a pendulab FMU (generated, one per archive).

The page describes the model, every variable (value reference, causality, variability, unit,
start, min, max, description: the same table the ``modelDescription.xml`` is built from), the
embedded solvers with their settings, and the limits of the FMU. The license file (FMI 3.0:
``documentation/licenses/license.txt``, used for FMI 2 archives too) covers pendulab's code,
the FMI headers (BSD-2, Modelica Association) and CasADi's generated code.
"""

from __future__ import annotations

import html

from .._version import __version__
from ..model.model import Model
from .codegen import SOLVER_NAMES, SPRING_LIMIT, ModelLayout
from .model_description import variables

__all__ = ["LICENSE_PATH", "binaries_html", "documentation_html", "license_text"]

#: Archive path of the license entry point (FMI 3.0 section 2.5; FMI 2 archives use the same place).
LICENSE_PATH = "documentation/licenses/license.txt"

_LICENSE = """pendulab FMU: license information
=================================

This archive holds code under three licenses.

1. pendulab (sources/fmi2.c, fmi3.c, fmu_core.[ch], ode_solver.[ch], model.h, *_functions.c, the
   binaries built from them, modelDescription.xml and this documentation): MIT License

   Copyright (c) the pendulab authors

   Permission is hereby granted, free of charge, to any person obtaining a copy of this software
   and associated documentation files (the "Software"), to deal in the Software without restriction,
   including without limitation the rights to use, copy, modify, merge, publish, distribute,
   sublicense, and/or sell copies of the Software, and to permit persons to whom the Software is
   furnished to do so, subject to the following conditions:

   The above copyright notice and this permission notice shall be included in all copies or
   substantial portions of the Software.

   THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR IMPLIED, INCLUDING BUT
   NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY, FITNESS FOR A PARTICULAR PURPOSE AND
   NONINFRINGEMENT. IN NO EVENT SHALL THE AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM,
   DAMAGES OR OTHER LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM, OUT
   OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE.

2. The FMI headers (sources/fmi2*.h, sources/fmi3*.h), unchanged from the Modelica Association's
   Reference FMUs: 2-Clause BSD License

   Copyright (C) 2008-2011 MODELISAR consortium,
                 2012-2023 Modelica Association Project "FMI"
                 All rights reserved.

   Redistribution and use in source and binary forms, with or without modification, are permitted
   provided that the following conditions are met:

   - Redistributions of source code must retain the above copyright notice, this list of conditions
     and the following disclaimer.

   - Redistributions in binary form must reproduce the above copyright notice, this list of
     conditions and the following disclaimer in the documentation and/or other materials provided
     with the distribution.

   THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS AND CONTRIBUTORS "AS IS" AND ANY EXPRESS OR
   IMPLIED WARRANTIES, INCLUDING, BUT NOT LIMITED TO, THE IMPLIED WARRANTIES OF MERCHANTABILITY AND
   FITNESS FOR A PARTICULAR PURPOSE ARE DISCLAIMED. IN NO EVENT SHALL THE COPYRIGHT HOLDER OR
   CONTRIBUTORS BE LIABLE FOR ANY DIRECT, INDIRECT, INCIDENTAL, SPECIAL, EXEMPLARY, OR CONSEQUENTIAL
   DAMAGES (INCLUDING, BUT NOT LIMITED TO, PROCUREMENT OF SUBSTITUTE GOODS OR SERVICES; LOSS OF USE,
   DATA, OR PROFITS; OR BUSINESS INTERRUPTION) HOWEVER CAUSED AND ON ANY THEORY OF LIABILITY,
   WHETHER IN CONTRACT, STRICT LIABILITY, OR TORT (INCLUDING NEGLIGENCE OR OTHERWISE) ARISING IN ANY
   WAY OUT OF THE USE OF THIS SOFTWARE, EVEN IF ADVISED OF THE POSSIBILITY OF SUCH DAMAGE.

3. CasADi-generated model functions (sources/model_casadi.c, model_adjoint_casadi.c): generated
   content is not copyrighted; the template code CasADi copies into them is licensed MIT-0 by
   the CasADi authors (see the header of those files).
"""


def license_text() -> bytes:
    """The license file of every FMU archive.

    Returns
    -------
    bytes
        UTF-8 text.
    """
    return _LICENSE.encode()


def _cell(value: object) -> str:
    return "" if value is None else html.escape(str(value))


def binaries_html(binaries: dict[str, str] | None) -> str:
    """The ``Binaries`` section of a documentation page: each binary and what it needs from the C runtime.

    Parameters
    ----------
    binaries : dict of str to str, optional
        Archive path (``binaries/<platform>/<file>``) -> requirement read from the built file
        (:func:`pendulab.fmu.platforms.runtime_requirement`, e.g. ``glibc >= 2.14``).

    Returns
    -------
    str
        HTML (``<h2 id="binaries">`` and a list); a sentence when the archive carries no binary.
    """
    items = "".join(
        f"<li><code>{html.escape(path)}</code>: needs {html.escape(need)}</li>" for path, need in sorted((binaries or {}).items())
    )
    return f"""<h2 id="binaries">Binaries</h2>
<ul>{items or "<li>none (sources only)</li>"}</ul>
<p>Read from each built file (ELF symbol versions, as <code>objdump -T</code> shows them; PE imports, as
<code>objdump -p</code>). Linux binaries built with Zig's C compiler (pendulab[cross]) target glibc 2.17
(manylinux2014); built with the system compiler they need the build machine's symbol versions. Windows DLLs built
by Zig import the Universal C Runtime (<code>api-ms-win-crt-*.dll</code>): part of Windows 10 and later, on
Windows 7 / 8.1 installed by update KB2999226 or any Visual C++ 2015+ redistributable (a DLL built by a mingw-w64
gcc imports the C runtime that toolchain defaults to, listed above).</p>"""


def documentation_html(
    model: Model,
    lay: ModelLayout,
    fmi_version: int,
    *,
    stop_time: float,
    step_size: float,
    binaries: dict[str, str] | None = None,
) -> bytes:
    """The FMU's ``documentation/index.html``.

    Parameters
    ----------
    model : Model
        The pendulum (names, units, descriptions).
    lay : ModelLayout
        Value references, start values, tunable flags.
    fmi_version : {2, 3}
        FMI standard of the archive.
    stop_time, step_size : float
        Default experiment [s].
    binaries : dict of str to str, optional
        What each binary of the archive needs from the C runtime (see :func:`binaries_html`).

    Returns
    -------
    bytes
        A self-contained UTF-8 HTML5 page (no scripts, no external resources).
    """
    rows = []
    for var in variables(model, lay, fmi_version):
        a = var.attrs
        rows.append(
            "<tr>"
            + "".join(
                f"<td>{_cell(v)}</td>"
                for v in (
                    var.name,
                    var.vr,
                    var.causality,
                    var.variability,
                    {"Real": "Float64", "Integer": "Int32"}.get(var.type, var.type) if fmi_version == 3 else var.type,
                    a.get("unit"),
                    a.get("start"),
                    a.get("min"),
                    a.get("max"),
                    var.description,
                )
            )
            + "</tr>"
        )
    elastic = model.kind == "elastic"
    title = f"{lay.identifier}: {model.kind} double pendulum (FMI {fmi_version}.0)"
    states = ", ".join(model.state_names)
    solvers = "".join(f"<li><code>solver = {i}</code>: {n}</li>" for i, n in enumerate(SOLVER_NAMES))
    spring = (
        "<li>Spring lengths <code>r1</code>, <code>r2</code> must stay &gt; 0 (the model is singular at r = 0): "
        "setters, <code>SetContinuousStates</code>, restored FMU states and each solver result are checked; "
        "a violation is <code>Error</code> with a log line.</li>"
        "<li>Events: the event indicators <code>spring_margin1</code>, <code>spring_margin2</code> "
        f"(r<sub>i</sub> &minus; {SPRING_LIMIT:g}&nbsp;L<sub>i</sub>) reach 0 when a spring is compressed to "
        f"{100 * SPRING_LIMIT:g} % of its rest length. Model Exchange: the importer locates the crossing and the "
        "FMU requests <code>terminateSimulation</code> in event mode. Co-Simulation: the step ends at the last of "
        "64 equal sub-steps before the limit; FMI 2 returns <code>Discard</code> with the "
        "<code>fmi2Terminated</code> status, FMI 3 returns early (when allowed, else <code>Discard</code>) with "
        "<code>terminateSimulation</code>.</li>"
        if elastic
        else "<li>The rigid model has no spring events.</li>"
    )
    if lay.flip_events:
        spring += (
            "<li>Flip events: <code>flip_margin1</code>, <code>flip_margin2</code> = &pi; &minus; |&theta;<sub>i</sub>| "
            "reach 0 when link i passes the upright position; Model Exchange importers stop there (nothing in the "
            "model changes). FMI 3 Co-Simulation with <code>eventModeUsed</code> and early return allowed: "
            "<code>DoStep</code> ends at each flip (bisection to 1e-12 s) with <code>eventHandlingNeeded</code>.</li>"
        )
    page = f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{html.escape(title)}</title>
<style>body{{font-family:sans-serif;max-width:70em;margin:auto}}table{{border-collapse:collapse}}
td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left}}code{{background:#f4f4f4}}</style>
</head>
<body>
<h1>{html.escape(title)}</h1>
<p>Generated by pendulab {html.escape(__version__)}. Co-Simulation (embedded solvers) and Model Exchange in one archive,
C sources included (<code>sources/</code>); no Python or CasADi runtime is needed.</p>

<h2 id="model">Model</h2>
<p>The {model.kind} double pendulum: {
        "two point masses on linear springs (Hooke) along the links, with spring dampers"
        if elastic
        else "two rigid links with point or distributed mass"
    }, joint dampers and the torques
<code>tau1</code> (ground&ndash;link 1) and <code>tau2</code> (link 1&ndash;link 2). The equations of motion are derived
from the kinetic and potential energy and the dissipation function by Lagrange's equations (CasADi, symbolically),
and the model functions are CasADi-generated C. Angles are absolute, measured from the downward vertical
(&theta; = (&pi;, &pi;) is upright). State: {html.escape(states)}. Outputs: bob positions (y up), total mechanical
energy{", spring stretches" if elastic else ""}.</p>

<h2 id="variables">Variables</h2>
<table>
<tr><th>name</th><th>value reference</th><th>causality</th><th>variability</th><th>type</th><th>unit</th><th>start</th>
<th>min</th><th>max</th><th>description</th></tr>
{chr(10).join(rows)}
</table>
<p>Bounds: <code>min = 5e-324</code> (the smallest positive double) stands for &ldquo;&gt; 0&rdquo;, since FMI has no
exclusive bound. Fixed parameters (masses, lengths{"" if elastic else ", lc1 lc2 I1 I2"}) may be set only before
<code>ExitInitializationMode</code>; tunable ones (g, dampers{", springs" if elastic else ""}) also in step and event
mode.</p>

<h2 id="solvers">Solvers (Co-Simulation)</h2>
<ul>{solvers}</ul>
<p>dopri5: Dormand&ndash;Prince 5(4), explicit, for rigid and soft-spring models. rodas4: Rosenbrock 4(3), L-stable,
with the exact generated Jacobian, for stiff springs. Error test: weighted RMS norm with atol = rtol = the
master's tolerance (<code>toleranceDefined</code>) or else <code>solver_tolerance</code> (default 1e-8);
<code>max_step</code> bounds the internal step (0: unlimited). Inputs are held constant over a communication step;
communication points are accepted with a relative tolerance of 1e-9. Default experiment: 0 to {stop_time:g} s,
step {step_size:g} s.</p>

<h2 id="limits">Limits</h2>
<ul>
<li>At most 100,000 internal solver steps per communication step (a step over a huge interval fails with
<code>Error</code>, &ldquo;too many internal steps&rdquo;, instead of running for a long time).</li>
{spring}
<li>Misuse (wrong state, unknown value reference, NULL arguments, NaN/Inf, out-of-range values) returns
<code>Error</code> with a message through the logger; a rejected multi-value set changes nothing.</li>
<li>FMU state: get/set/serialize; a restored state resumes the life-cycle state it was taken in.</li>
<li>Directional derivatives of derivatives and outputs with respect to states and inputs.</li>
</ul>
{binaries_html(binaries)}
<p>License: <a href="licenses/license.txt">licenses/license.txt</a>.</p>
</body>
</html>
"""
    return page.encode()
