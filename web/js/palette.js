// Every colour the plots and pages draw with: one colour-blind-safe palette (Okabe & Ito 2008,
// "Color Universal Design") for categorical data, and the few marks that are not categories.
// The app's chrome (text, panels, badges) is coloured in css/app.css, with the same accent.

// The Okabe-Ito colours, in the order categories take them.
export const OKABE_ITO = {
  blue: "#0072B2", orange: "#E69F00", bluishGreen: "#009E73", reddishPurple: "#CC79A7",
  vermillion: "#D55E00", skyBlue: "#56B4E9", yellow: "#F0E442", black: "#000000",
};
export const CATEGORICAL = [OKABE_ITO.blue, OKABE_ITO.orange, OKABE_ITO.bluishGreen, OKABE_ITO.reddishPurple,
  OKABE_ITO.vermillion, OKABE_ITO.skyBlue, OKABE_ITO.yellow, OKABE_ITO.black];

// The i-th value of a category gets the i-th colour.
function categories(values) {
  return Object.fromEntries(values.map((v, i) => [v, CATEGORICAL[i]]));
}

export const ACTIONS = ["pull", "push", "show me", "slide"];
export const OBJECT_COLOURS = ["blue", "green", "red", "yellow"];
export const SHAPES = ["apple", "banana", "dice", "phone"];

export const ACTION_COLOURS = categories(ACTIONS);
export const SHAPE_COLOURS = categories(SHAPES);
export const MODE_COLOURS = categories(["faithful", "end_to_end", "peer"]);
export const SPLIT_COLOURS = categories(["train", "test"]);
// An object is drawn in its own colour: the palette's shade of that name.
export const COLOUR_COLOURS = {
  blue: OKABE_ITO.blue, green: OKABE_ITO.bluishGreen, red: OKABE_ITO.vermillion, yellow: OKABE_ITO.yellow,
};
// The latent explorer shows the action by the marker's symbol (and the object colour by its colour).
export const ACTION_SYMBOLS = { pull: "circle", push: "square", "show me": "diamond", slide: "triangle-up" };
// What each way of grouping the corpus colours its points by (the Csc plots' "colour by").
export const BY = { action: ACTION_COLOURS, colour: COLOUR_COLOURS, shape: SHAPE_COLOURS, object: SHAPE_COLOURS,
  split: SPLIT_COLOURS };

// Marks that are not categories.
export const ACCENT = "#3056a0"; // css/app.css --accent
export const NEUTRAL = "#999999"; // an unknown category, an input signal, what is kept apart
export const HIGHLIGHT = OKABE_ITO.black; // the picked recording, the probe
export const CURSOR = OKABE_ITO.vermillion; // the shared time cursor, a moved point
export const WHITE = "#ffffff";
export const TRANSPARENT = "rgba(0,0,0,0)";
// Magnitudes on a continuous scale (heatmaps of features and unit activity): perceptually uniform,
// readable with every colour-vision deficiency and in grey.
export const SEQUENTIAL = "Viridis";
// Share of exact descriptions, 0 -> 1.
export const EXACT_SCALE = [[0, OKABE_ITO.vermillion], [0.5, OKABE_ITO.yellow], [1, OKABE_ITO.bluishGreen]];

// The colour of `value` in `colours`, NEUTRAL when it is not one of its categories.
export function colourOf(colours, value) {
  return colours[value] ?? NEUTRAL;
}
