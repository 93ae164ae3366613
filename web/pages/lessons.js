// Lessons page of the app's navigation: the seven lessons live in web/lessons/ (also /lessons/).
export { meta, render } from "../lessons/lessons.js";
