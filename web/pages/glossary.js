// Glossary: the words of the paper the app uses, each with an anchor the "?" buttons link to.

import { h } from "../js/dom.js";

export const meta = { route: "glossary", title: "Glossary", order: 90, description: "the terms of the model" };

export const TERMS = [
  ["MTRNN", "Multiple timescale recurrent neural network (Yamashita & Tani 2008): a continuous-time RNN whose units leak at different speeds. Three layers: input-output (IO, fast), context-fast (Cf) and context-slow (Cs). Each unit's internal state moves towards its input by 1/tau per step (eq. 3)."],
  ["timescale", "tau, how slowly a unit changes: z_t = (1 - 1/tau) z_{t-1} + (1/tau) (input). Small tau (2 for IO) follows every step; large tau (16 to 70 for Cs) integrates over the whole sequence. The paper's Table 1: MTRNN_a 2/5/70, MTRNN_s 2/5/50, MTRNN_v 2/5/16 for IO/Cf/Cs. This hierarchy of speeds is what lets slow units hold a sequence's gist while fast units handle its detail."],
  ["Csc", "Context-controlling units: the slowest units of the Cs layer (12 per network here). In MTRNN_s and MTRNN_v their final internal state c_T abstracts the whole perceived sequence (context abstraction). In MTRNN_a their initial state c_0 decides which utterance is produced (context bias). The Csc explorer plots these patterns for every recording."],
  ["context bias", "Using an MTRNN as a generator: the Csc units start at c_0 and the network runs closed-loop, producing a sequence (here: phonemes). Different c_0, different utterance."],
  ["context abstraction", "The paper's reversal of context bias (3.2): the network reads a sequence and its Csc units accumulate a pattern c_T at the last step, a concept of the whole sequence. Trained with self-organisation forcing (psi)."],
  ["cell assembly", "Densely connected neurons that stand for one concept across modalities (Hebb, Pulvermüller). In the model: a linear map from the sensory Csc states (c_s,T and c_v,T, through the sigmoid) to the auditory c_a,0 (eqs. 16-17). It fuses and disambiguates what each sense alone leaves ambiguous."],
  ["psi", "Self-organisation forcing constant (eqs. 11-12). The encoders' Csc targets c_T are not fixed: a share psi of the error moves the targets, 1 - psi trains the weights. Too small: targets stay random; too large: they collapse together. The paper finds psi_v = 5e-5 and psi_s = 5e-4 best."],
  ["phoneme", "A speech sound of the ARPAbet (from the CMU pronouncing dictionary), plus signs for silence (SIL) and sentence ends (PER, EXM, QUM): the alphabet B, one output neuron each. An utterance is encoded as a Gaussian spike per phoneme, every 2 steps, softmax-normalised per step (eqs. 18-21); MTRNN_a's output is decoded back by taking the winning neuron."],
  ["proprioception", "The sense of one's own body: here the five joint angles of the NAO's right arm (RShoulderPitch, RShoulderRoll, RElbowYaw, RElbowRoll, RWristYaw) at 20 frames per second, scaled to [0, 1] by the joint limits. MTRNN_s reads it. It tells the manipulations apart but barely the objects, as in the paper."],
  ["vision features", "Per camera frame (Fig. 7): mean-shift segmentation, Canny edges and the contour finder isolate the object; 16 distances from its centre of mass to the contour (one per 22.5 degrees, scaled by the square root of the area, largest first) describe the shape, and the mean R, G, B its colour. 19 values for MTRNN_v, plus the centroid."],
  ["PCA", "Principal component analysis: the Csc patterns (12 numbers each) rotated so that the first axes carry the most variance; PC1 and PC2 are drawn. Exact SVD, deterministic signs. The inverse maps a point of the plane back to a pattern (latent explorer)."],
  ["split", "The model is trained on half of the 64 scenes (all four recordings of a scene on the same side) and tested on the other half, whose action, colour and shape combinations it never saw. Test scenes measure generalisation."],
  ["teacher forcing", "During training of MTRNN_a, the output fed back at each step mixes a share alpha = 0.1 of the desired output into the generated one (eq. 5). At generation time alpha = 0: the network runs on its own output."],
  ["d_avg, d_rel, d_inter, d_intra", "Distances between Csc patterns (eqs. 13-15, 22-23): d_avg the mean pairwise distance, d_rel how evenly spread they are (1 = all equal), d_inter the spread inside each manipulation's cluster, d_intra the distance between the clusters' centroids."],
];

const slug = (t) => t.toLowerCase().replace(/[^a-z0-9]+/g, "-");

export function render(root, ctx) {
  root.append(h("h1", {}, "Glossary"),
    h("dl", { class: "glossary" }, TERMS.map(([term, text]) => [
      h("dt", { id: `term-${slug(term)}` }, term), h("dd", {}, text)])));
  const wanted = ctx.params.term;
  if (wanted) {
    const el = document.getElementById(`term-${slug(wanted)}`);
    if (el) { el.classList.add("highlight"); el.scrollIntoView({ block: "center" }); }
  }
}
