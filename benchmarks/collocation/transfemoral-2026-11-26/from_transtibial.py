"""Transfemoral 4 m/s from the transtibial Cat6 4 m/s stride (an alternating run): the common
coordinates copied by name, the prosthetic knee from the transtibial's residual knee, the
pelvis lowered until a contact is 1 cm deep at every node, the template's force pattern.

    python from_transtibial.py benchmarks/collocation/study-2026-11-25-cat6-starts/\
        amputee-Cat6/speed-4.warm-mu-1e-4.json track|notrack

(session 9; writes into /work/exp9/tf/, as run; docs/design.md, "Predicted transfemoral
gaits")."""
import json, sys, numpy as np
from bladelab.runner import build_runner
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.guess import StrideGuess, periodic_derivative
from bladelab.predict.collocation.solve import CollocationSettings, predict_stride
from bladelab.design.predicted import stride_responses
src = CollocationSolution.read(sys.argv[1])
tf = build_runner("transfemoral")
q = np.zeros((src.nlp.q.shape[0], len(tf.dof_names)))
for j, n in enumerate(tf.dof_names):
    q[:, j] = src.nlp.q[:, src.dof_names.index(n)]
from bladelab.predict.collocation.guess import _grounded, template_vertical_grf
q = _grounded(tf, q)
q[:, tf.dof("pelvis_tz")] -= 0.01
g = StrideGuess("transtibial stride on the transfemoral runner", src.period_s, q,
                periodic_derivative(q, src.period_s), vertical_grf_bw=template_vertical_grf(np.linspace(0, 1, q.shape[0])))
track = sys.argv[2] == "track"
sol = predict_stride(tf, CollocationSettings(mesh_intervals=50, speed_m_per_s=4.0, swing_clearance_m=0.02),
                     g, model_spec={"model": "transfemoral", "blade": "Cat4"}, track=track)
print(json.dumps(sol.summary()), flush=True)
if sol.converged:
    print(json.dumps(stride_responses(sol, tf)))
sol.write(f"/work/exp9/tf/from-tt-{sys.argv[2]}.json")
