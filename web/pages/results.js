// Results page of the app's navigation: the view lives in web/js/results.js (also web/results.html).
import { renderResults } from "../js/results.js";

export const meta = { route: "results", title: "Results", order: 90,
  description: "the evaluation report's figures, interactive" };

export function render(root) {
  return renderResults(root);
}
