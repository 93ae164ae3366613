// Jobs page of the app's navigation: the view lives in web/js/jobs.js (also web/jobs.html).
import { renderJobs } from "../js/jobs.js";

export const meta = { route: "jobs", title: "Jobs", order: 80,
  description: "train or evaluate models, watch them learn, serve a new model" };

export function render(root) {
  return renderJobs(root);
}
