"""The OpenFOAM side of bench/peers/openfoam/openfoam_bench.py: the dictionaries it writes from a
coloc case and what it reads back. A coloc case file (load_jsonc) becomes an OpenFOAM case: each
file under the FoamFile HEADER (foam_file), one box's blockMeshDict (box_mesh), the controlDict
(control_dict), then the whole icoFoam case of the channel (write_channel) and the DPMFoam case of
the fluidised bed with its particle cloud (write_fbed). Read back: the per-step CPU and wall
times of a solver's log from its ExecutionTime / ClockTime lines (foam_steps, per_step_foam) and
the particle positions DPMFoam writes (foam_positions).
"""
import json
import os
import re

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))  # HEADER's case path is from here

HEADER = """/*--------------------------------*- C++ -*----------------------------------*\\
  Written by bench/peers/openfoam/openfoam_bench.py from {case}
\\*---------------------------------------------------------------------------*/
FoamFile
{{
    version     2.0;
    format      ascii;
    class       {cls};
    location    "{loc}";
    object      {obj};
}}
"""


def load_jsonc(path):
    """coloc case files are JSON with // comments (never inside strings in bench/cases)."""
    text = open(path).read()
    text = re.sub(r"//[^\n]*", "", text)
    return json.loads(text)


def foam_file(case_dir, rel, body, case, cls="dictionary"):
    path = os.path.join(case_dir, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    loc, obj = os.path.split(rel)
    with open(path, "w") as f:
        f.write(HEADER.format(case=os.path.relpath(case, ROOT), cls=cls, loc=loc, obj=obj))
        f.write(body.strip("\n") + "\n")


def box_mesh(origin, length, cells, patches):
    """blockMeshDict of one box; patches: {face: (name, type)} for xlo..zhi."""
    x0, y0, z0 = origin
    x1, y1, z1 = (o + l for o, l in zip(origin, length))
    faces = {"xlo": "(0 4 7 3)", "xhi": "(1 2 6 5)", "ylo": "(0 1 5 4)", "yhi": "(3 7 6 2)",
             "zlo": "(0 3 2 1)", "zhi": "(4 5 6 7)"}
    by = {}
    for face, (name, typ) in patches.items():
        by.setdefault((name, typ), []).append(faces[face])
    bnd = "\n".join(f"    {n}\n    {{\n        type {t};\n        faces\n        (\n" +
                    "\n".join(f"            {fc}" for fc in fcs) + "\n        );\n    }"
                    for (n, t), fcs in by.items())
    return f"""
scale 1;
vertices
(
    ({x0} {y0} {z0}) ({x1} {y0} {z0}) ({x1} {y1} {z0}) ({x0} {y1} {z0})
    ({x0} {y0} {z1}) ({x1} {y0} {z1}) ({x1} {y1} {z1}) ({x0} {y1} {z1})
);
blocks ( hex (0 1 2 3 4 5 6 7) ({cells[0]} {cells[1]} {cells[2]}) simpleGrading (1 1 1) );
edges ();
boundary
(
{bnd}
);
"""


def control_dict(app, dt, steps, write_at_end=False):
    end = dt * steps
    wi = f"{steps}" if write_at_end else f"{10 * steps}"
    return f"""
application     {app};
startFrom       startTime;
startTime       0;
stopAt          endTime;
endTime         {end:.10g};
deltaT          {dt:.10g};
writeControl    timeStep;
writeInterval   {wi};
purgeWrite      0;
writeFormat     ascii;
writePrecision  10;
writeCompression off;
timeFormat      general;
timePrecision   10;
runTimeModifiable false;
"""


# ----------------------------------------------------------------------------------------------
# channel: icoFoam


def channel_fv_solution(tol, n_correctors, p_reltol):
    """icoFoam's fvSolution: GAMG for p at coloc's tolerance. p_reltol > 0 (0.05 by default in
    openfoam_bench.py) is how icoFoam's users run it (the tutorials' cavity: p relTol 0.05 on the
    first correctors, pFinal relTol 0 on the last one, all to the same tolerance); p_reltol = 0
    solves every corrector to the tolerance (the setting of the first comparison, issue 16)."""
    if p_reltol > 0:
        note = f"""// p: coloc's fluid.pressure.tol = {tol:g} as an absolute tolerance on OpenFOAM's normalised
// residual (sum|b - A x| / normFactor, itself scaled by the size of A x and b). As icoFoam's
// users run it (the PISO settings of tutorials/incompressible/icoFoam/cavity: p relTol 0.05,
// pFinal relTol 0, 2 correctors; GAMG rather than the tutorial's PCG + DIC, as for a mesh of
// this size): each corrector before the last stops at relTol {p_reltol:g} (of its first
// residual) or at the tolerance, the last (pFinal) at the tolerance alone: the step ends at a
// residual {tol:g} of the scale of the equation, as coloc's single projection does."""
    else:
        note = f"""// p: coloc's fluid.pressure.tol = {tol:g} as an absolute tolerance on OpenFOAM's normalised
// residual (sum|b - A x| / normFactor, itself scaled by the size of A x and b), relTol 0 on
// every corrector: both stop at a residual {tol:g} of the scale of the equation (the setting
// of the first comparison; --p-reltol 0)."""
    return f"""
{note}
solvers
{{
    p     {{ solver GAMG; tolerance {tol:g}; relTol {p_reltol:g}; smoother GaussSeidel; }}
    pFinal {{ $p; relTol 0; }}
    U     {{ solver smoothSolver; smoother symGaussSeidel; tolerance 1e-05; relTol 0; }}
}}
PISO
{{
    nCorrectors     {n_correctors};
    nNonOrthogonalCorrectors 0;
    pRefCell        0;
    pRefValue       0;
}}
"""


def write_channel(case, cfg, dt, steps, n_correctors, d, p_reltol=0.05):
    fl, dom = cfg["fluid"], cfg["domain"]
    tol = fl["pressure"]["tol"]
    names = {}
    for face, b in fl["boundary"].items():
        names[face] = {"inlet": ("inlet", "patch"), "outlet": ("outlet", "patch"),
                       "wall": ("walls", "wall")}[b["type"]]
    inlet = next(b for b in fl["boundary"].values() if b["type"] == "inlet")["velocity"]
    p_out = next(b for b in fl["boundary"].values() if b["type"] == "outlet").get("pressure", 0)
    u0 = fl.get("initial_velocity", [0, 0, 0])
    vec = lambda v: "(" + " ".join(f"{x:g}" for x in v) + ")"
    foam_file(d, "system/blockMeshDict",
              box_mesh(dom.get("origin", [0, 0, 0]), dom["length"], dom["cells"], names), case)
    foam_file(d, "system/controlDict", control_dict("icoFoam", dt, steps), case)
    foam_file(d, "system/fvSchemes", """
ddtSchemes      { default Euler; }
gradSchemes     { default Gauss linear; }
divSchemes      { default none; div(phi,U) Gauss vanLeerV; }  // coloc: TVD, van Leer limiter
laplacianSchemes { default Gauss linear corrected; }
interpolationSchemes { default linear; }
snGradSchemes   { default corrected; }
""", case)
    foam_file(d, "system/fvSolution", channel_fv_solution(tol, n_correctors, p_reltol), case)
    foam_file(d, "constant/transportProperties", f"nu [0 2 -1 0 0 0 0] {fl['nu']:g};", case)
    bc_u = {"inlet": f"type fixedValue; value uniform {vec(inlet)};",
            "outlet": "type zeroGradient;", "walls": "type noSlip;"}
    bc_p = {"inlet": "type zeroGradient;", "outlet": f"type fixedValue; value uniform {p_out:g};",
            "walls": "type zeroGradient;"}
    pats = sorted({n for n, _ in names.values()})
    foam_file(d, "0/U", "dimensions [0 1 -1 0 0 0 0];\n"
              f"internalField uniform {vec(u0)};\nboundaryField\n{{\n" +
              "".join(f"    {p} {{ {bc_u[p]} }}\n" for p in pats) + "}", case, "volVectorField")
    foam_file(d, "0/p", "dimensions [0 2 -2 0 0 0 0];\ninternalField uniform 0;\n"
              "boundaryField\n{\n" + "".join(f"    {p} {{ {bc_p[p]} }}\n" for p in pats) + "}",
              case, "volScalarField")


def foam_steps(log):
    """Per-step (cpu, wall) increments from ExecutionTime/ClockTime lines, and the log text."""
    text = open(log).read()
    ex = [(float(a), float(b)) for a, b in
          re.findall(r"ExecutionTime = ([0-9.eE+-]+) s\s+ClockTime = ([0-9.eE+-]+) s", text)]
    return ex, text


def per_step_foam(log, skip=1, tail=0):
    """Per-step CPU and wall s over the steps after the first `skip` and before the last `tail`
    (ExecutionTime lines: one after each time step, the first also holding the start-up, a
    step that writes also holding the writing)."""
    ex, text = foam_steps(log)
    last = len(ex) - 1 - tail
    n = last - (skip - 1)
    cpu = (ex[last][0] - ex[skip - 1][0]) / n
    wall = (ex[last][1] - ex[skip - 1][1]) / n
    return cpu, wall, n, text


# ----------------------------------------------------------------------------------------------
# fbed: DPMFoam


def fbed_fv_solution(tol, n_correctors, p_reltol):
    """DPMFoam's fvSolution. p_reltol > 0 (with 2 correctors: openfoam_bench.py's default) is
    how DPMFoam's users run it: the solver settings of its one tutorial in v1912,
    lagrangian/DPMFoam/Goldschmidt (PIMPLE, 1 outer corrector, 2 PISO correctors; GAMG p relTol
    0.01 then pFinal relTol 0; U relTol 0.1, U Final relTol 0), at coloc's pressure tolerance;
    p_reltol 0 with 1 corrector is the setting of the first comparison (issue 16)."""
    if p_reltol > 0:
        note = f"""// As DPMFoam's users run it: the solver settings of its v1912 tutorial
// (lagrangian/DPMFoam/Goldschmidt, the only DPMFoam tutorial): PIMPLE with 1 outer and
// {n_correctors} PISO correctors, GAMG p relTol {p_reltol:g} on the correctors before the last and
// pFinal relTol 0 (the step ends at the tolerance), U relTol 0.1 / Final 0 (with one outer
// corrector the momentum solve is the final one: relTol 0). The tolerance is coloc's
// fluid.pressure.tol ({tol:g}; the tutorial's is 1e-6). Drag and time step are chosen to match
// coloc, not the tutorial (kinematicCloudProperties; openfoam_bench.py --foam-dt)."""
        u_rel = 0.1
    else:
        note = f"""// Every corrector to coloc's pressure tolerance ({tol:g}, relTol 0), {n_correctors} corrector(s)
// (the setting of the first comparison; --p-reltol 0 --n-correctors 1)."""
        u_rel = 0
    return f"""
{note}
solvers
{{
    p      {{ solver GAMG; tolerance {tol:g}; relTol {p_reltol:g}; smoother GaussSeidel; }}
    pFinal {{ $p; relTol 0; }}
    U.air  {{ solver smoothSolver; smoother symGaussSeidel; tolerance 1e-05; relTol {u_rel:g}; }}
    // written out: a macro naming U.air would read the entry air of a dictionary U
    U.airFinal {{ solver smoothSolver; smoother symGaussSeidel; tolerance 1e-05; relTol 0; }}
    "kinematicCloud:theta.*" {{ solver GAMG; tolerance 1e-06; relTol 0;
                               smoother GaussSeidel; }}
}}
PIMPLE
{{
    nOuterCorrectors 1;
    nCorrectors     {n_correctors};
    momentumPredictor yes;
    nNonOrthogonalCorrectors 0;
    pRefCell        0;
    pRefValue       0;
}}
relaxationFactors {{}}
"""


def write_fbed(case, cfg, d, dt, steps, radius, alpha, collision_steps, drag, n_correctors=2,
               p_reltol=0.01):
    dom, fl, pa = cfg["domain"], cfg["fluid"], cfg["particles"]
    mat = pa["materials"][0]
    names = {}
    for face, b in fl["boundary"].items():
        names[face] = {"inlet": ("bottom", "patch"), "outlet": ("top", "patch"),
                       "wall": ("walls", "wall")}[b["type"]]
    inlet = next(b for b in fl["boundary"].values() if b["type"] == "inlet")["velocity"]
    vec = lambda v: "(" + " ".join(f"{x:g}" for x in v) + ")"
    foam_file(d, "system/blockMeshDict",
              box_mesh(dom.get("origin", [0, 0, 0]), dom["length"], dom["cells"], names), case)
    foam_file(d, "system/controlDict", control_dict("DPMFoam", dt, steps, write_at_end=True),
              case)
    foam_file(d, "system/fvSchemes", """
ddtSchemes      { default Euler; }
gradSchemes     { default Gauss linear; }
divSchemes
{
    default         none;
    div(alphaPhi.air,U.air) Gauss vanLeerV;
    div(((alpha.air*nuEff.air)*dev2(T(grad(U.air))))) Gauss linear;
}
laplacianSchemes { default Gauss linear corrected; }
interpolationSchemes { default linear; }
snGradSchemes   { default corrected; }
""", case)
    tol = fl.get("pressure", {}).get("tol", 1e-8)
    foam_file(d, "system/fvSolution", fbed_fv_solution(tol, n_correctors, p_reltol), case)
    foam_file(d, "constant/transportProperties",
              f"continuousPhase air;\nrho.air {fl['rho']:g};\ntransportModel Newtonian;\n"
              f"nu {fl['nu']:g};", case)
    foam_file(d, "constant/turbulenceProperties.air", "simulationType laminar;", case)
    foam_file(d, "constant/g", f"dimensions [0 1 -2 0 0 0 0];\nvalue {vec(cfg['gravity'])};",
              case, "uniformDimensionedVectorField")
    pats = sorted({n for n, _ in names.values()})
    bc_u = {"bottom": f"type interstitialInletVelocity; inletVelocity uniform {vec(inlet)}; "
                      f"value uniform {vec(inlet)}; phi phi.air; alpha alpha.air;",
            "top": "type pressureInletOutletVelocity; phi phi.air; inletValue uniform (0 0 0); "
                   "value uniform (0 0 0);",
            "walls": "type noSlip;"}
    bc_p = {"bottom": "type fixedFluxPressure; value uniform 0;",
            "top": "type fixedValue; value uniform 0;",
            "walls": "type fixedFluxPressure; value uniform 0;"}
    foam_file(d, "0/U.air", "dimensions [0 1 -1 0 0 0 0];\n"
              f"internalField uniform {vec(fl.get('initial_velocity', [0, 0, 0]))};\n"
              "boundaryField\n{\n" + "".join(f"    {p} {{ {bc_u[p]} }}\n" for p in pats) + "}",
              case, "volVectorField")
    foam_file(d, "0/p", "dimensions [0 2 -2 0 0 0 0];\ninternalField uniform 0;\n"
              "boundaryField\n{\n" + "".join(f"    {p} {{ {bc_p[p]} }}\n" for p in pats) + "}",
              case, "volScalarField")
    E, nu_p, mu = mat["young"], mat["poisson"], mat["friction"]
    walls = "\n".join(f"            {p} {{ type rebound; e {mat['restitution']:g}; mu {mu:g}; }}"
                      for p in pats)
    foam_file(d, "constant/kinematicCloudProperties", f"""
solution
{{
    active          true;
    coupled         true;
    transient       yes;
    cellValueSourceCorrection off;
    interpolationSchemes {{ rho.air cell; U.air cellPoint; mu.air cell; }}
    integrationSchemes {{ U Euler; }}
    sourceTerms {{ schemes {{ U semiImplicit 1; }} }}
}}
constantProperties
{{
    parcelTypeId    1;
    rhoMin          1e-15;
    minParcelMass   1e-15;
    rho0            {mat['density']:g};
    youngsModulus   {E:g};
    poissonsRatio   {nu_p:g};
    constantVolume  false;
    alphaMax        0.99;
}}
subModels
{{
    particleForces
    {{
        {drag} {{ alphac alpha.air; }}   // coloc: Di Felice (the closest: a power of eps on a
                                         // single-sphere drag, no Ergun branch)
        gravity;
    }}
    injectionModels
    {{
        settled
        {{
            type            manualInjection;
            massTotal       0;
            parcelBasisType fixed;
            nParticle       1;
            SOI             0;
            positionsFile   "kinematicCloudPositions";   // coloc's settled bed
            U0              (0 0 0);
            sizeDistribution
            {{
                type fixedValue;
                fixedValueDistribution {{ value {2 * radius:g}; }}
            }}
        }}
    }}
    dispersionModel none;
    patchInteractionModel standardWallInteraction;   // walls: pairCollision's wall model
    standardWallInteractionCoeffs {{ type rebound; e {mat['restitution']:g}; mu {mu:g}; }}
    localInteractionCoeffs {{ patches ( {walls} ); }}
    heatTransferModel none;
    surfaceFilmModel none;
    stochasticCollisionModel none;
    radiation off;
    collisionModel  pairCollision;
    pairCollisionCoeffs
    {{
        maxInteractionDistance  {2 * radius:g};
        writeReferredParticleCloud no;
        pairModel pairSpringSliderDashpot;
        pairSpringSliderDashpotCoeffs
        {{
            useEquivalentSize   no;
            alpha               {alpha:g};   // damping: restitution ~{mat['restitution']:g}
            b                   1.5;        // Hertz
            mu                  {mu:g};
            cohesionEnergyDensity 0;
            collisionResolutionSteps {collision_steps};
        }}
        wallModel wallSpringSliderDashpot;
        wallSpringSliderDashpotCoeffs
        {{
            useEquivalentSize   no;
            collisionResolutionSteps {collision_steps};
            youngsModulus       {E:g};
            poissonsRatio       {nu_p:g};
            alpha               {alpha:g};
            b                   1.5;
            mu                  {mu:g};
            cohesionEnergyDensity 0;
        }}
        U U.air;
    }}
}}
cloudFunctions {{}}
""", case)


def foam_positions(case_dir, time_name):
    """Cartesian positions DPMFoam wrote at time_name (the legacy `positions` file)."""
    import numpy as np
    path = os.path.join(case_dir, time_name, "lagrangian", "kinematicCloud", "positions")
    text = open(path).read()
    pts = re.findall(r"\(\s*([-0-9.eE+]+)\s+([-0-9.eE+]+)\s+([-0-9.eE+]+)\s*\)", text)
    return np.array(pts, dtype=float)
